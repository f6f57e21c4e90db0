// The lattice machinery shared by the adaptive tessellator's files: lattice points, the quadtree's
// cell geometry, a cell's triangles per edge-split configuration, and the error kernels
// (error_kernels.cpp) that measure a triangle or an unsplit cell against the texels. Internal to
// the tessellate stage.
#pragma once

#include <algorithm>
#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <limits>

#include <lightvol/tessellate/adaptive_grid.h>

namespace lightvol::detail {

// A texel, as a lattice point (col, row).
struct Pt {
  int x = 0, y = 0;
};

// Cell geometry of a grid of cw × ch quads (W−1 × H−1).
struct Quadtree {
  int cw = 0, ch = 0, top = 0;

  Quadtree(int width, int height) : cw(width - 1), ch(height - 1) {
    while ((1 << top) < std::max(cw, ch)) ++top;
  }
  int nx(int level) const { return (cw + (1 << level) - 1) >> level; }
  int ny(int level) const { return (ch + (1 << level) - 1) >> level; }
  std::size_t cells(int level) const {
    return static_cast<std::size_t>(nx(level)) * static_cast<std::size_t>(ny(level));
  }
  struct Box {
    int x0, y0, x1, y1;
  };
  Box box(int level, int i, int j) const {
    const int s = 1 << level;
    return {i * s, j * s, std::min(i * s + s, cw), std::min(j * s + s, ch)};
  }
};

// The texels of row y inside the closed triangle v[0], v[1], v[2] (counter-clockwise in texel
// space: each directed edge p→q keeps the points with cross(q − p, x − p) ≥ 0, i.e. A·x + C ≥ 0):
// [*x0, *x1], or false when the row holds none. Exact: integer arithmetic throughout.
inline bool triangle_row_span(const Pt v[3], int y, int* x0, int* x1) {
  const auto floor_div = [](std::int64_t a, std::int64_t b) {  // b > 0
    return a >= 0 ? a / b : -((-a + b - 1) / b);
  };
  std::int64_t lo = std::numeric_limits<int>::min(), hi = std::numeric_limits<int>::max();
  for (int k = 0; k < 3; ++k) {
    const Pt p = v[k], q = v[(k + 1) % 3];
    const std::int64_t ex = q.x - p.x, ey = q.y - p.y;
    const std::int64_t A = -ey, C = ex * (y - p.y) + ey * p.x;
    if (A > 0) {
      lo = std::max(lo, -floor_div(C, A));  // ceil(−C / A)
    } else if (A < 0) {
      hi = std::min(hi, floor_div(C, -A));
    } else if (C < 0) {
      return false;
    }
  }
  if (lo > hi) return false;
  *x0 = static_cast<int>(lo);
  *x1 = static_cast<int>(hi);
  return true;
}

// triangle_row_span for consecutive rows y, y + 1, ... of a triangle's row range (between its
// lowest and highest corner), without a division per row: each edge's bound floor(C(y) / |A|) is
// kept as a quotient and a remainder, and C grows by the same amount every row. A horizontal edge
// (A = 0) excludes no row of that range, so only the two or three others are walked; with a single
// edge on one side, it is walked twice (the max or min of equal bounds). Exact: the same spans as
// triangle_row_span.
class RowSpanWalker {
 public:
  RowSpanWalker(const Pt v[3], int y) {
    const auto floor_div = [](std::int64_t a, std::int64_t b) {  // b > 0
      return a >= 0 ? a / b : -((-a + b - 1) / b);
    };
    int nlo = 0, nhi = 0;
    for (int k = 0; k < 3; ++k) {
      const Pt p = v[k], q = v[(k + 1) % 3];
      const std::int64_t ex = q.x - p.x, ey = q.y - p.y;
      const std::int64_t A = -ey, C = ex * (y - p.y) + ey * p.x;
      if (A == 0) continue;
      Edge& e = A > 0 ? lo_[nlo++] : hi_[nhi++];
      e.d = A > 0 ? A : -A;
      e.q = floor_div(C, e.d), e.r = C - e.q * e.d;
      e.dq = floor_div(ex, e.d), e.dr = ex - e.dq * e.d;
    }
    if (nlo == 1) lo_[1] = lo_[0];
    if (nhi == 1) hi_[1] = hi_[0];
  }

  // The span of the current row (false: none), then moves to the next row.
  bool next(int* x0, int* x1) {
    const std::int64_t lo = std::max(-lo_[0].q, -lo_[1].q), hi = std::min(hi_[0].q, hi_[1].q);
    for (Edge& e : lo_) e.step();
    for (Edge& e : hi_) e.step();
    *x0 = static_cast<int>(lo);
    *x1 = static_cast<int>(hi);
    return lo <= hi;
  }

 private:
  struct Edge {  // floor(C / d) = q, remainder r; per row C grows by dq·d + dr
    std::int64_t q = 0, r = 0, d = 1, dq = 0, dr = 0;
    void step() {
      q += dq, r += dr;
      if (r >= d) r -= d, ++q;
    }
  };
  Edge lo_[2], hi_[2];  // edges with A > 0 (bound −q on x) and A < 0 (bound q)
};

// The largest error (TexelDepths::error) over the texels (lattice points) of the closed triangle
// (a, b, c), whose window depth is the plane through its corners' depths: exactly what the
// emitted flat triangle gives along each texel ray. Large triangles split their rows across
// threads. The triangle must have nonzero area.
double triangle_error(const TexelDepths& t, Pt a, Pt b, Pt c);

// The largest error over the texels of an unsplit cell `b` (both triangles of
// cell_triangles(config 0)), rows [y_begin, y_end) only. The rows stop as soon as the error so far
// exceeds `cap`: a result above `cap` is then only known to be at most the cell's error. With
// `depth_gap`, also the largest |plane − depth| over those rows in window depth (unscaled).
double box_error_rows(const TexelDepths& t, const Quadtree::Box& b, int y_begin, int y_end,
                      double cap = std::numeric_limits<double>::infinity(),
                      double* depth_gap = nullptr);

// `e` rounded up to a float (a pyramid value never understates the error it stands for).
float round_up(double e);

// Edge-split bits of a cell's configuration.
enum : unsigned { kSplitTop = 1, kSplitRight = 2, kSplitBottom = 4, kSplitLeft = 8 };

// The triangles of a cell in configuration `config`, positively oriented in (col, row) (the
// static grid's standard winding): the diagonal runs from the top-right to the bottom-left corner
// like the static grid's quads, and each split edge fans its midpoint to the opposite corner of its
// half. Returns the count (2 + number of split edges).
inline int cell_triangles(const Quadtree::Box& b, int half, unsigned config,
                          std::array<Pt, 3>* out) {
  const Pt a{b.x0, b.y0}, bb{b.x1, b.y0}, c{b.x0, b.y1}, d{b.x1, b.y1};
  const Pt mt{b.x0 + half, b.y0}, mr{b.x1, b.y0 + half}, mb{b.x0 + half, b.y1},
      ml{b.x0, b.y0 + half};
  int n = 0;
  const bool top = config & kSplitTop, right = config & kSplitRight, bottom = config & kSplitBottom,
             left = config & kSplitLeft;
  // Upper-left half (a, b, c): top and left edges.
  if (top && left) {
    out[n++] = {a, mt, ml}, out[n++] = {mt, bb, ml}, out[n++] = {ml, bb, c};
  } else if (top) {
    out[n++] = {a, mt, c}, out[n++] = {mt, bb, c};
  } else if (left) {
    out[n++] = {a, bb, ml}, out[n++] = {ml, bb, c};
  } else {
    out[n++] = {a, bb, c};
  }
  // Lower-right half (b, d, c): right and bottom edges.
  if (right && bottom) {
    out[n++] = {mr, d, mb}, out[n++] = {bb, mr, mb}, out[n++] = {bb, mb, c};
  } else if (right) {
    out[n++] = {bb, mr, c}, out[n++] = {mr, d, c};
  } else if (bottom) {
    out[n++] = {bb, d, mb}, out[n++] = {bb, mb, c};
  } else {
    out[n++] = {bb, d, c};
  }
  return n;
}

inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace lightvol::detail
