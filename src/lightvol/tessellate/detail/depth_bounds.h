// Bounds of the texels' window depths over aligned blocks, and a test that proves a triangle
// within an error bound from them and its corners alone: the shortcut of the exact texel tests of
// the quadtree's fix-up (quadtree.cpp) and the collapse (collapse_grid.cpp). Internal to the
// tessellate stage.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <vector>

#include <tbb/parallel_for.h>

#include <lightvol/core/buffer.h>
#include <lightvol/tessellate/adaptive_grid.h>
#include <lightvol/tessellate/detail/lattice.h>

namespace lightvol::detail {

// The least and greatest window depth of the texels in aligned square blocks of 2^L × 2^L texels,
// L from kFirst up to one block, as floats rounded outwards (a bound, not the exact values): a
// pyramid of minima and maxima, about 1/32 of the texels' floats.
class DepthBounds {
 public:
  static constexpr int kFirst = 3;

  void build(const TexelDepths& t) {
    if (t.float_depths()) {
      build_as<float>(t);
    } else {
      build_as<double>(t);
    }
  }

  bool empty() const { return levels_.empty(); }

  // Bounds of the depths of the texels in [x0, x1] × [y0, y1]: the blocks of the level where the
  // box spans at most three blocks each way (two at the first level).
  void range(int x0, int y0, int x1, int y1, double* lo, double* hi) const {
    const int s = std::max(x1 - x0, y1 - y0) + 1;
    std::size_t k = 0;
    while (k + 1 < levels_.size() && (2 << (kFirst + k)) < s) ++k;
    const Level& l = levels_[k];
    const int shift = kFirst + static_cast<int>(k);
    float a = std::numeric_limits<float>::infinity(), b = -a;
    for (int by = y0 >> shift; by <= y1 >> shift; ++by)
      for (int bx = x0 >> shift; bx <= x1 >> shift; ++bx) {
        const std::size_t c = static_cast<std::size_t>(by) * static_cast<std::size_t>(l.nx) + bx;
        a = std::min(a, l.lo[c]);
        b = std::max(b, l.hi[c]);
      }
    *lo = a, *hi = b;
  }

 private:
  struct Level {
    int nx, ny;
    std::vector<float> lo, hi;
  };

  template <class D>
  void build_as(const TexelDepths& t) {
    const int w = t.width(), h = t.height();
    int nx = (w + (1 << kFirst) - 1) >> kFirst, ny = (h + (1 << kFirst) - 1) >> kFirst;
    levels_.clear();
    levels_.push_back({nx, ny, {}, {}});
    Level& first = levels_.back();
    resize_large(first.lo, static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny));
    resize_large(first.hi, first.lo.size());
    // Each block row: the columns' least and greatest depth over its rows (element-wise, in D),
    // then each block's over its columns, rounded outwards to float once.
    tbb::parallel_for(0, ny, [&](int by) {
      std::vector<D> col_lo(t.depth_row_as<D>(by << kFirst), t.depth_row_as<D>(by << kFirst) + w);
      std::vector<D> col_hi = col_lo;
      for (int y = (by << kFirst) + 1; y < std::min((by + 1) << kFirst, h); ++y) {
        const D* row = t.depth_row_as<D>(y);
        D* cl = col_lo.data();
        D* ch = col_hi.data();
        for (int x = 0; x < w; ++x) {  // vectorizes: x < y ? x : y is the min instruction
          cl[x] = row[x] < cl[x] ? row[x] : cl[x];
          ch[x] = row[x] > ch[x] ? row[x] : ch[x];
        }
      }
      const std::size_t at = static_cast<std::size_t>(by) * static_cast<std::size_t>(nx);
      for (int bx = 0; bx < nx; ++bx) {
        D a = col_lo[static_cast<std::size_t>(bx) << kFirst],
          b = col_hi[static_cast<std::size_t>(bx) << kFirst];
        for (int x = (bx << kFirst) + 1; x < std::min((bx + 1) << kFirst, w); ++x) {
          a = std::min(a, col_lo[static_cast<std::size_t>(x)]);
          b = std::max(b, col_hi[static_cast<std::size_t>(x)]);
        }
        float down = static_cast<float>(a), up = static_cast<float>(b);
        if (static_cast<D>(down) > a) down = std::nextafter(down, -1.0f);
        if (static_cast<D>(up) < b) up = std::nextafter(up, 2.0f);
        first.lo[at + static_cast<std::size_t>(bx)] = down;
        first.hi[at + static_cast<std::size_t>(bx)] = up;
      }
    });
    while (nx > 1 || ny > 1) {
      const Level& fine = levels_.back();
      const int cnx = (nx + 1) / 2, cny = (ny + 1) / 2;
      Level coarse{cnx, cny, {}, {}};
      resize_large(coarse.lo, static_cast<std::size_t>(cnx) * static_cast<std::size_t>(cny));
      resize_large(coarse.hi, coarse.lo.size());
      for (int by = 0; by < cny; ++by)
        for (int bx = 0; bx < cnx; ++bx) {
          float lo = std::numeric_limits<float>::infinity(), hi = -lo;
          for (int y = 2 * by; y < std::min(2 * by + 2, ny); ++y)
            for (int x = 2 * bx; x < std::min(2 * bx + 2, nx); ++x) {
              const std::size_t k = static_cast<std::size_t>(y) * static_cast<std::size_t>(nx) + x;
              lo = std::min(lo, fine.lo[k]);
              hi = std::max(hi, fine.hi[k]);
            }
          const std::size_t k = static_cast<std::size_t>(by) * static_cast<std::size_t>(cnx) + bx;
          coarse.lo[k] = lo;
          coarse.hi[k] = hi;
        }
      levels_.push_back(std::move(coarse));
      nx = cnx, ny = cny;
    }
  }

  std::vector<Level> levels_;
};

// Whether the triangle's texels are within the bound by its corners' depths alone (uniform
// error scale): its plane lies between its least and greatest corner depth over the triangle,
// and its texels' depths between the least and greatest depth of the blocks covering its
// bounding box, so no texel's error exceeds the larger distance between those two ranges.
// Uniform error scales only (t.uniform()). The exact tests (triangle_within in collapse_grid.cpp,
// triangle_error) compute each texel's error with rounding: the plane's gradient has an
// absolute error of a few units of 2^-53 times (largest extent)² / twice the area (depths lie
// in [0, 1]), and so has the plane's value across the box; the margin, 1e-13·(1 + extent² /
// twice the area) in depth, is hundreds of times that, and the product with the scale gets a
// relative margin of 1e-12. So a true here means the exact test finds the triangle within the
// bound (the same fix-up splits, collapses and flips); a false means nothing, and the texels are
// measured.
inline bool within_by_bounds(const TexelDepths& t, const DepthBounds& bounds, Pt a, Pt b, Pt c,
                             double bound) {
  const double da = t.window_depth(a.x, a.y), db = t.window_depth(b.x, b.y),
               dc = t.window_depth(c.x, c.y);
  const int x0 = std::min({a.x, b.x, c.x}), x1 = std::max({a.x, b.x, c.x});
  const int y0 = std::min({a.y, b.y, c.y}), y1 = std::max({a.y, b.y, c.y});
  double lo = 0, hi = 0;
  bounds.range(x0, y0, x1, y1, &lo, &hi);
  const double spread = std::max(std::max({da, db, dc}) - lo, hi - std::min({da, db, dc}));
  const std::int64_t cross =
      std::int64_t{b.x - a.x} * (c.y - a.y) - std::int64_t{c.x - a.x} * (b.y - a.y);
  const double area2 = static_cast<double>(cross < 0 ? -cross : cross);
  const double extent = std::max(x1 - x0, y1 - y0);
  const double margin = 1e-13 * (1 + extent * extent / area2);
  return (spread + margin) * t.uniform_scale() * (1 + 1e-12) <= bound;
}

}  // namespace lightvol::detail
