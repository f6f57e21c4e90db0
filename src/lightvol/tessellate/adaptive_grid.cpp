#include <sys/mman.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <lightvol/core/check.h>
#include <lightvol/tessellate/adaptive_grid.h>

namespace lightvol {

namespace {

// An array of n doubles left uninitialized (the caller's parallel loop is the first touch),
// advised onto transparent huge pages when large: fewer page faults. Advice only.
std::unique_ptr<double[]> uninitialized_array(std::size_t n) {
  auto a = std::make_unique_for_overwrite<double[]>(n);
  constexpr std::uintptr_t kHuge = std::uintptr_t{2} << 20;
  const auto begin = reinterpret_cast<std::uintptr_t>(a.get());
  const std::uintptr_t aligned = (begin + kHuge - 1) & ~(kHuge - 1);
  const std::uintptr_t end = (begin + n * sizeof(double)) & ~(kHuge - 1);
  if (end > aligned + 4 * kHuge)
    ::madvise(reinterpret_cast<void*>(aligned), end - aligned, MADV_HUGEPAGE);
  return a;
}

}  // namespace

// ---- texel depths ------------------------------------------------------------------------------

Result<TexelDepths> TexelDepths::create(const Light& light, const DepthImage& image, int face,
                                        const std::string& source) {
  const int w = image.width, h = image.height;
  LV_CHECK(w >= 2 && h >= 2);
  TexelDepths t;
  t.width_ = w;
  t.height_ = h;
  const std::size_t n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  t.depth_ = uninitialized_array(n);

  // clip → world. A texel's homogeneous point at window depth d is h0 + d·h1 with
  // h0 = M·(x_ndc, y_ndc, −1, 1) and h1 = 2·M·e_z; two points of one ray lie
  // |d1 − d2|·|h1.xyz·h0.w − h0.xyz·h1.w| / |w(d1)·w(d2)| apart.
  const Mat4d view = light.type == LightType::omni ? omni_face_view(light, face) : light.view;
  bool ok = false;
  const Mat4d inv_view = inverse(view, &ok);
  LV_CHECK(ok);
  const Mat4d inv_proj = inverse(light.projection, &ok);
  LV_CHECK(ok);
  const Mat4d m = inv_view * inv_proj;
  const double h1[4] = {2 * m(0, 2), 2 * m(1, 2), 2 * m(2, 2), 2 * m(3, 2)};
  const double sy = light.flip_y ? 1.0 : -1.0;
  const auto xn = [w](int c) { return (2.0 * c + 1.0) / w - 1.0; };
  const auto yn = [h, sy](int r) { return sy * ((2.0 * r + 1.0) / h - 1.0); };
  t.w0_dc_ = m(3, 0) * 2.0 / w;
  t.w0_dr_ = m(3, 1) * sy * 2.0 / h;
  t.w0_c_ = m(3, 0) * xn(0) + m(3, 1) * yn(0) - m(3, 2) + m(3, 3);
  t.w1_ = h1[3];
  t.uniform_ = m(3, 0) == 0 && m(3, 1) == 0 && h1[3] == 0;
  if (t.uniform_) {
    t.uniform_scale_ = std::sqrt(h1[0] * h1[0] + h1[1] * h1[1] + h1[2] * h1[2]) / std::abs(t.w0_c_);
  } else {
    t.scale_ = uninitialized_array(n);
  }

  const bool window = light.depth == DepthEncoding::window;
  const Mat4d& pj = light.projection;
  const bool linear_fast = light.depth == DepthEncoding::linear && pj(2, 0) == 0 && pj(2, 1) == 0 &&
                           pj(3, 0) == 0 && pj(3, 1) == 0;
  const double pz = pj(2, 2), pzc = pj(2, 3), pw = pj(3, 2), pwc = pj(3, 3);
  const Unprojector unproject(light, w, h, face, Space::world);
  std::atomic<std::size_t> first_bad{std::numeric_limits<std::size_t>::max()};
  tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
    for (int r = rows.begin(); r != rows.end(); ++r) {
      for (int c = 0; c < w; ++c) {
        const std::size_t v = t.index(c, r);
        const double stored = image.values[v];
        double d = 0;
        if (window) {
          d = std::clamp(stored, 0.0, 1.0);
        } else if (linear_fast) {
          // The projection's z and w rows see only the eye depth z = −stored.
          const double z = -std::clamp(stored, light.near, light.far);
          d = std::clamp(0.5 * ((pz * z + pzc) / (pw * z + pwc) + 1.0), 0.0, 1.0);
        } else {
          Vec3d p;
          if (!unproject.point(c, r, stored, &p)) {
            std::size_t seen = first_bad.load();
            while (v < seen && !first_bad.compare_exchange_weak(seen, v)) {
            }
            p = unproject.near_point(c, r);
          }
          const Vec3d e = view.transform_point(p);
          const Mat4d& pr = light.projection;
          const double z = pr(2, 0) * e.x + pr(2, 1) * e.y + pr(2, 2) * e.z + pr(2, 3);
          const double ww = pr(3, 0) * e.x + pr(3, 1) * e.y + pr(3, 2) * e.z + pr(3, 3);
          d = std::clamp(0.5 * (z / ww + 1.0), 0.0, 1.0);
        }
        t.depth_[v] = d;
        if (!t.uniform_) {
          const double x = xn(c), y = yn(r);
          double h0[4];
          for (int k = 0; k < 4; ++k) h0[k] = m(k, 0) * x + m(k, 1) * y - m(k, 2) + m(k, 3);
          const Vec3d g{h1[0] * h0[3] - h0[0] * h1[3], h1[1] * h0[3] - h0[1] * h1[3],
                        h1[2] * h0[3] - h0[2] * h1[3]};
          t.scale_[v] = length(g) / std::abs(h0[3] + d * h1[3]);
        }
      }
    }
  });
  if (const std::size_t bad = first_bad.load(); bad != std::numeric_limits<std::size_t>::max()) {
    return Error{source + ": pixel (" + std::to_string(bad % w) + ", " + std::to_string(bad / w) +
                 "): radial depth " + std::to_string(image.values[bad]) +
                 " is shorter than the texel ray's distance from the light position"};
  }
  return t;
}

// ---- triangles over the lattice ----------------------------------------------------------------

namespace {

struct Pt {
  int x = 0, y = 0;
};

std::int64_t floor_div(std::int64_t a, std::int64_t b) {  // b > 0
  return a >= 0 ? a / b : -((-a + b - 1) / b);
}
std::int64_t ceil_div(std::int64_t a, std::int64_t b) { return -floor_div(-a, b); }

// The largest error over the texels (lattice points) of the closed triangle (a, b, c), rows
// [y_begin, y_end) only. The triangle's window depth is the plane through its corners' depths:
// exactly what the emitted flat triangle gives along each texel ray.
template <bool kUniform>
double triangle_error_rows(const TexelDepths& t, Pt a, Pt b, Pt c, int y_begin, int y_end) {
  std::int64_t area2 =
      std::int64_t{b.x - a.x} * (c.y - a.y) - std::int64_t{c.x - a.x} * (b.y - a.y);
  if (area2 < 0) {
    std::swap(b, c);
    area2 = -area2;
  }
  LV_CHECK(area2 > 0);
  const double da = t.window_depth(a.x, a.y), db = t.window_depth(b.x, b.y),
               dc = t.window_depth(c.x, c.y);
  const double inv = 1.0 / static_cast<double>(area2);
  const double gx = ((db - da) * (c.y - a.y) - (dc - da) * (b.y - a.y)) * inv;
  const double gy = ((dc - da) * (b.x - a.x) - (db - da) * (c.x - a.x)) * inv;
  const Pt v[3] = {a, b, c};
  double worst = 0;
  for (int y = y_begin; y < y_end; ++y) {
    // Each directed edge p→q keeps the points with cross(q − p, x − p) ≥ 0: A·x + C ≥ 0.
    std::int64_t lo = std::numeric_limits<int>::min(), hi = std::numeric_limits<int>::max();
    for (int k = 0; k < 3; ++k) {
      const Pt p = v[k], q = v[(k + 1) % 3];
      const std::int64_t ex = q.x - p.x, ey = q.y - p.y;
      const std::int64_t A = -ey, C = ex * (y - p.y) + ey * p.x;
      if (A > 0) {
        lo = std::max(lo, ceil_div(-C, A));
      } else if (A < 0) {
        hi = std::min(hi, floor_div(C, -A));
      } else if (C < 0) {
        lo = 1, hi = 0;
      }
    }
    if (lo > hi) continue;
    const int x0 = static_cast<int>(lo), x1 = static_cast<int>(hi);
    const double* dt = t.depth_row(y);
    const double base = da + gy * (y - a.y) + gx * (x0 - a.x);
    double m = 0;
    if constexpr (kUniform) {
#pragma omp simd reduction(max : m)
      for (int x = x0; x <= x1; ++x) {
        const double e = std::abs(base + gx * (x - x0) - dt[x]);
        m = m > e ? m : e;
      }
    } else {
      const double* k = t.scale_row(y);
      const double w0 = t.w0(x0, y), dw = t.w0_dc(), w1 = t.w1();
#pragma omp simd reduction(max : m)
      for (int x = x0; x <= x1; ++x) {
        const double d = base + gx * (x - x0);
        const double e = std::abs(d - dt[x]) * k[x] / std::abs(w0 + dw * (x - x0) + d * w1);
        m = m > e ? m : e;
      }
    }
    worst = std::max(worst, m);
  }
  if constexpr (kUniform) worst *= t.uniform_scale();
  return worst;
}

double triangle_error(const TexelDepths& t, Pt a, Pt b, Pt c) {
  const int y0 = std::min({a.y, b.y, c.y}), y1 = std::max({a.y, b.y, c.y}) + 1;
  const int x0 = std::min({a.x, b.x, c.x}), x1 = std::max({a.x, b.x, c.x}) + 1;
  const auto rows = [&](int ya, int yb) {
    return t.uniform() ? triangle_error_rows<true>(t, a, b, c, ya, yb)
                       : triangle_error_rows<false>(t, a, b, c, ya, yb);
  };
  // Large triangles (the top of the pyramid) split their rows across threads.
  if (static_cast<std::int64_t>(y1 - y0) * (x1 - x0) < (1 << 16)) return rows(y0, y1);
  return tbb::parallel_reduce(
      tbb::blocked_range<int>(y0, y1, 16), 0.0,
      [&](const tbb::blocked_range<int>& r, double m) {
        return std::max(m, rows(r.begin(), r.end()));
      },
      [](double p, double q) { return std::max(p, q); });
}

float round_up(double e) {
  float f = static_cast<float>(e);
  if (static_cast<double>(f) < e) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

// ---- the quadtree ------------------------------------------------------------------------------

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

// The largest error over the texels of an unsplit cell (rows [y_begin, y_end)): the upper-left
// triangle (a, b, c) and the lower-right one (b, d, c) of cell_triangles(config 0), without the
// general triangle's span arithmetic. Each texel is taken once; on the diagonal both planes agree.
template <bool kUniform>
double box_error_rows_t(const TexelDepths& t, const Quadtree::Box& b, int y_begin, int y_end) {
  const int wx = b.x1 - b.x0, wy = b.y1 - b.y0;
  const double da = t.window_depth(b.x0, b.y0), db = t.window_depth(b.x1, b.y0),
               dc = t.window_depth(b.x0, b.y1), dd = t.window_depth(b.x1, b.y1);
  const double g1x = (db - da) / wx, g1y = (dc - da) / wy;  // a + g1·(p − a)
  const double g2x = (dd - dc) / wx, g2y = (dd - db) / wy;  // d + g2·(p − d)
  double worst = 0;
  for (int y = y_begin; y < y_end; ++y) {
    const int s = y - b.y0;
    const int xs =
        b.x0 + (wx == wy ? wy - s : static_cast<int>((std::int64_t{wx} * (wy - s)) / wy));
    const double* dt = t.depth_row(y);
    const double base1 = da + g1y * s, base2 = dd + g2y * (y - b.y1);
    double m = 0;
    if constexpr (kUniform) {
#pragma omp simd reduction(max : m)
      for (int x = b.x0; x <= xs; ++x) {
        const double e = std::abs(base1 + g1x * (x - b.x0) - dt[x]);
        m = m > e ? m : e;
      }
#pragma omp simd reduction(max : m)
      for (int x = xs + 1; x <= b.x1; ++x) {
        const double e = std::abs(base2 + g2x * (x - b.x1) - dt[x]);
        m = m > e ? m : e;
      }
    } else {
      const double* k = t.scale_row(y);
      const double w1 = t.w1();
      const double w0y = t.w0(0, y), w0dc = t.w0_dc();
#pragma omp simd reduction(max : m)
      for (int x = b.x0; x <= xs; ++x) {
        const double d = base1 + g1x * (x - b.x0);
        const double e = std::abs(d - dt[x]) * k[x] / std::abs(w0y + w0dc * x + d * w1);
        m = m > e ? m : e;
      }
#pragma omp simd reduction(max : m)
      for (int x = xs + 1; x <= b.x1; ++x) {
        const double d = base2 + g2x * (x - b.x1);
        const double e = std::abs(d - dt[x]) * k[x] / std::abs(w0y + w0dc * x + d * w1);
        m = m > e ? m : e;
      }
    }
    worst = std::max(worst, m);
  }
  if constexpr (kUniform) worst *= t.uniform_scale();
  return worst;
}

double box_error_rows(const TexelDepths& t, const Quadtree::Box& b, int y_begin, int y_end) {
  return t.uniform() ? box_error_rows_t<true>(t, b, y_begin, y_end)
                     : box_error_rows_t<false>(t, b, y_begin, y_end);
}

// Edge-split bits of a cell's configuration.
enum : unsigned { kSplitTop = 1, kSplitRight = 2, kSplitBottom = 4, kSplitLeft = 8 };

// The triangles of a cell in configuration `config`, positively oriented in (col, row) (the
// static grid's standard winding): the diagonal runs from the top-right to the bottom-left corner
// like the static grid's quads, and each split edge fans its midpoint to the opposite corner of its
// half. Returns the count (2 + number of split edges).
int cell_triangles(const Quadtree::Box& b, int half, unsigned config, std::array<Pt, 3>* out) {
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

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

std::uint32_t AdaptiveGrid::vertex_index(int col, int row) const {
  const std::uint32_t id = static_cast<std::uint32_t>(row) * static_cast<std::uint32_t>(width) +
                           static_cast<std::uint32_t>(col);
  const auto it = std::lower_bound(vertices.begin(), vertices.end(), id);
  LV_CHECK(it != vertices.end() && *it == id);
  return static_cast<std::uint32_t>(it - vertices.begin());
}

// ---- the pyramid -------------------------------------------------------------------------------

RefinementPyramid::RefinementPyramid(TexelDepths texels, Refinement refinement)
    : texels_(std::move(texels)), refinement_(refinement) {
  const auto start = std::chrono::steady_clock::now();
  const int w = texels_.width(), h = texels_.height();
  const Quadtree q(w, h);
  top_ = q.top;
  value_.resize(static_cast<std::size_t>(top_) + 1);

  // Laplacian mode: the edge map of window depth (neighbours clamped at the border).
  std::vector<float> edges;
  if (refinement_ == Refinement::laplacian) {
    edges.resize(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
    tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
      for (int r = rows.begin(); r != rows.end(); ++r)
        for (int c = 0; c < w; ++c) {
          const auto at = [&](int cc, int rr) {
            return texels_.window_depth(std::clamp(cc, 0, w - 1), std::clamp(rr, 0, h - 1));
          };
          const double lap =
              at(c - 1, r) + at(c + 1, r) + at(c, r - 1) + at(c, r + 1) - 4 * at(c, r);
          edges[static_cast<std::size_t>(r) * w + c] = round_up(std::abs(lap));
        }
    });
  }

  for (int level = 1; level <= top_; ++level) value_[level].assign(q.cells(level), 0.0f);

  // One cell: its own measure (max_error: over both triangles of its unsplit configuration;
  // laplacian, level 1: the edge map over its texels), then the max with its children.
  const auto compute = [&](int level, int i, int j) {
    const Quadtree::Box b = q.box(level, i, j);
    float v = 0;
    if (refinement_ == Refinement::max_error && level == 1 && b.x1 - b.x0 == 2 &&
        b.y1 - b.y0 == 2) {
      // A whole level-1 cell: five texels, each halfway along an edge or the diagonal.
      const TexelDepths& t = texels_;
      const int x = b.x0, y = b.y0;
      const double da = t.window_depth(x, y), db = t.window_depth(x + 2, y),
                   dc = t.window_depth(x, y + 2), dd = t.window_depth(x + 2, y + 2);
      const double e =
          std::max({t.error(x + 1, y, 0.5 * (da + db)), t.error(x, y + 1, 0.5 * (da + dc)),
                    t.error(x + 1, y + 1, 0.5 * (db + dc)), t.error(x + 2, y + 1, 0.5 * (db + dd)),
                    t.error(x + 1, y + 2, 0.5 * (dc + dd))});
      v = round_up(e);
    } else if (refinement_ == Refinement::max_error) {
      v = round_up(box_error_rows(texels_, b, b.y0, b.y1 + 1));
    } else if (level == 1) {
      for (int y = b.y0; y <= b.y1; ++y)
        for (int x = b.x0; x <= b.x1; ++x)
          v = std::max(v, edges[static_cast<std::size_t>(y) * w + x]);
    }
    if (level > 1) {
      const std::vector<float>& below = value_[level - 1];
      const int nxb = q.nx(level - 1), nyb = q.ny(level - 1);
      for (int cj = 2 * j; cj < std::min(2 * j + 2, nyb); ++cj)
        for (int ci = 2 * i; ci < std::min(2 * i + 2, nxb); ++ci)
          v = std::max(v, below[static_cast<std::size_t>(cj) * nxb + ci]);
    }
    value_[level][static_cast<std::size_t>(j) * q.nx(level) + i] = v;
  };

  // Levels 1..K tile by tile: a level-K cell's texels stay in cache while its whole sub-pyramid is
  // computed. The levels above K in one sweep over the rows: each row adds its texels to the own
  // measure of its cell at every upper level (partial maxima per chunk of rows, joined by max:
  // exact and deterministic), so the texels are read once more, not once per level.
  const int tile = std::min(top_, 6);
  if (tile >= 1) {
    const int ntx = q.nx(tile);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, q.cells(tile)),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        for (std::size_t t = range.begin(); t != range.end(); ++t) {
                          const int ti = static_cast<int>(t % ntx), tj = static_cast<int>(t / ntx);
                          for (int level = 1; level <= tile; ++level) {
                            const int span = 1 << (tile - level);
                            const int i1 = std::min((ti + 1) * span, q.nx(level)),
                                      j1 = std::min((tj + 1) * span, q.ny(level));
                            for (int j = tj * span; j < j1; ++j)
                              for (int i = ti * span; i < i1; ++i) compute(level, i, j);
                          }
                        }
                      });
  }
  if (top_ > tile && refinement_ == Refinement::max_error) {
    using Own = std::vector<std::vector<double>>;  // per upper level, per cell
    Own empty(static_cast<std::size_t>(top_) + 1);
    for (int level = tile + 1; level <= top_; ++level) empty[level].assign(q.cells(level), 0.0);
    const Own own = tbb::parallel_reduce(
        tbb::blocked_range<int>(0, h, 16), empty,
        [&](const tbb::blocked_range<int>& rows, Own acc) {
          for (int y = rows.begin(); y != rows.end(); ++y)
            for (int level = tile + 1; level <= top_; ++level) {
              const int nx = q.nx(level), ny = q.ny(level), j = y >> level;
              for (int cj : {j - 1, j}) {
                if (cj < 0 || cj >= ny) continue;
                if (cj == j - 1 && (y & ((1 << level) - 1)) != 0) continue;  // not its bottom edge
                for (int i = 0; i < nx; ++i) {
                  double& m = acc[level][static_cast<std::size_t>(cj) * nx + i];
                  m = std::max(m, box_error_rows(texels_, q.box(level, i, cj), y, y + 1));
                }
              }
            }
          return acc;
        },
        [](Own a, const Own& b) {
          for (std::size_t l = 0; l < a.size(); ++l)
            for (std::size_t c = 0; c < a[l].size(); ++c) a[l][c] = std::max(a[l][c], b[l][c]);
          return a;
        });
    for (int level = tile + 1; level <= top_; ++level)
      for (std::size_t c = 0; c < own[level].size(); ++c)
        value_[level][c] = round_up(own[level][c]);
  }
  for (int level = tile + 1; level <= top_; ++level) {
    // Upper levels: the max with the children (own measures are in place).
    const int nx = q.nx(level), nxb = q.nx(level - 1), nyb = q.ny(level - 1);
    for (std::size_t cell = 0; cell < q.cells(level); ++cell) {
      const int i = static_cast<int>(cell % nx), j = static_cast<int>(cell / nx);
      float v = value_[level][cell];
      for (int cj = 2 * j; cj < std::min(2 * j + 2, nyb); ++cj)
        for (int ci = 2 * i; ci < std::min(2 * i + 2, nxb); ++ci)
          v = std::max(v, value_[level - 1][static_cast<std::size_t>(cj) * nxb + ci]);
      value_[level][cell] = v;
    }
  }
  seconds_ = seconds_since(start);
}

// ---- tessellation ------------------------------------------------------------------------------

AdaptiveGrid RefinementPyramid::tessellate(double bound, bool standard,
                                           const BorderSplits& forced) const {
  const auto start = std::chrono::steady_clock::now();
  const int w = texels_.width(), h = texels_.height();
  const Quadtree q(w, h);
  const int top = q.top;
  AdaptiveGrid grid;
  grid.width = w;
  grid.height = h;

  // split[L][cell]: the cell (level ≥ 1) is divided into its children.
  std::vector<std::vector<std::uint8_t>> split(static_cast<std::size_t>(top) + 1);
  for (int level = 1; level <= top; ++level) {
    const std::vector<float>& v = value_[level];
    std::vector<std::uint8_t>& s = split[level];
    s.resize(v.size());
    for (std::size_t c = 0; c < v.size(); ++c) s[c] = v[c] > bound ? 1 : 0;
  }
  const auto is_split = [&](int level, int i, int j) {
    if (level < 1 || i < 0 || j < 0 || i >= q.nx(level) || j >= q.ny(level)) return false;
    return split[level][static_cast<std::size_t>(j) * q.nx(level) + i] != 0;
  };
  const auto set_split = [&](int level, int i, int j) {
    split[level][static_cast<std::size_t>(j) * q.nx(level) + i] = 1;
  };

  // Forced border vertices: split every cell along the side whose interior holds the texel.
  for (int side = 0; side < 4; ++side) {
    const int length = (side == kTop || side == kBottom) ? q.cw : q.ch;
    for (const int p : forced.side[side]) {
      LV_CHECK(p >= 0 && p <= length);
      if (p == 0 || p == length) continue;
      for (int level = top; level >= 1 && (p & ((1 << level) - 1)) != 0; --level) {
        const int k = p >> level;
        switch (side) {
          case kTop:
            set_split(level, k, 0);
            break;
          case kBottom:
            set_split(level, k, q.ny(level) - 1);
            break;
          case kLeft:
            set_split(level, 0, k);
            break;
          default:
            set_split(level, q.nx(level) - 1, k);
            break;
        }
      }
    }
  }

  // Configuration of a leaf: the edges whose same-level neighbour is split and whose midpoint
  // is a texel inside the (clipped) edge.
  const auto config_of = [&](int level, int i, int j, const Quadtree::Box& b) {
    if (level == 0) return 0u;
    const int half = 1 << (level - 1);
    unsigned config = 0;
    if (b.x0 + half < b.x1) {
      if (is_split(level, i, j - 1)) config |= kSplitTop;
      if (is_split(level, i, j + 1)) config |= kSplitBottom;
    }
    if (b.y0 + half < b.y1) {
      if (is_split(level, i - 1, j)) config |= kSplitLeft;
      if (is_split(level, i + 1, j)) config |= kSplitRight;
    }
    return config;
  };

  // Leaves by blocks: a block is one row of level-(L+1) cells, whose unsplit children are the
  // leaves of level L there (the root alone for the top level). Order: coarse levels first, rows
  // and cells in order: deterministic.
  struct Block {
    int level, row;
  };
  std::vector<Block> blocks{{top, 0}};
  for (int level = top - 1; level >= 0; --level)
    for (int j = 0; j < q.ny(level + 1); ++j) blocks.push_back({level, j});
  const auto for_each_leaf = [&](const Block& blk, auto&& fn) {
    const int level = blk.level;
    if (level == top) {
      if (!is_split(top, 0, 0)) fn(0, 0);
      return;
    }
    const int pnx = q.nx(level + 1), nx = q.nx(level), ny = q.ny(level);
    const std::uint8_t* prow = split[level + 1].data() + static_cast<std::size_t>(blk.row) * pnx;
    for (int pi = 0; pi < pnx; ++pi) {
      if (!prow[pi]) continue;
      for (int cj = 2 * blk.row; cj < std::min(2 * blk.row + 2, ny); ++cj)
        for (int ci = 2 * pi; ci < std::min(2 * pi + 2, nx); ++ci)
          if (!is_split(level, ci, cj)) fn(ci, cj);
    }
  };

  const bool bounded = refinement_ == Refinement::max_error;
  for (;;) {
    // 2:1 balance: a split cell needs its four same-level neighbours to exist, so their parents
    // split; and a split cell's parent splits. One sweep from fine to coarse settles every level.
    for (int level = 2; level <= top; ++level) {
      const int nx = q.nx(level);
      std::vector<std::uint8_t>& s = split[level];
      tbb::parallel_for(
          tbb::blocked_range<std::size_t>(0, s.size(), 1024),
          [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t cell = range.begin(); cell != range.end(); ++cell) {
              if (s[cell]) continue;
              const int i = static_cast<int>(cell % nx), j = static_cast<int>(cell / nx);
              const int l = level - 1, ci = 2 * i, cj = 2 * j;
              const bool any = is_split(l, ci, cj) || is_split(l, ci + 1, cj) ||
                               is_split(l, ci, cj + 1) || is_split(l, ci + 1, cj + 1) ||
                               is_split(l, ci - 1, cj) || is_split(l, ci - 1, cj + 1) ||
                               is_split(l, ci + 2, cj) || is_split(l, ci + 2, cj + 1) ||
                               is_split(l, ci, cj - 1) || is_split(l, ci + 1, cj - 1) ||
                               is_split(l, ci, cj + 2) || is_split(l, ci + 1, cj + 2);
              if (any) s[cell] = 1;
            }
          });
    }
    if (!bounded) break;

    // Fix-up: a leaf whose split configuration breaks the bound splits as well (its children meet
    // the bound with their own triangles: the pyramid's values never grow downwards).
    std::vector<std::vector<std::uint8_t>> fail(split.size());
    for (int level = 1; level <= top; ++level) fail[level].assign(split[level].size(), 0);
    const bool any_fail = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, blocks.size(), 1), false,
        [&](const tbb::blocked_range<std::size_t>& range, bool acc) {
          for (std::size_t k = range.begin(); k != range.end(); ++k) {
            const int level = blocks[k].level;
            // Level 1 never fails: every configuration keeps the diagonal, and the texels that are
            // not vertices (unsplit edge midpoints, the centre on the diagonal) interpolate as in
            // the unsplit cell.
            if (level <= 1) continue;
            for_each_leaf(blocks[k], [&](int i, int j) {
              const Quadtree::Box b = q.box(level, i, j);
              const unsigned config = config_of(level, i, j, b);
              if (config == 0) return;
              // With a uniform error scale, a configuration moves the surface by at most the
              // deviation of its split midpoints, texels of the cell: its error is at most twice
              // the cell's own (≤ its pyramid value v). 2v within the bound needs no evaluation.
              const double v = value_[level][static_cast<std::size_t>(j) * q.nx(level) + i];
              if (texels_.uniform() && 2 * v * (1 + 1e-9) <= bound) return;
              std::array<Pt, 3> tri[6];
              const int n = cell_triangles(b, 1 << (level - 1), config, tri);
              for (int t = 0; t < n; ++t) {
                if (triangle_error(texels_, tri[t][0], tri[t][1], tri[t][2]) > bound) {
                  fail[level][static_cast<std::size_t>(j) * q.nx(level) + i] = 1;
                  acc = true;
                  return;
                }
              }
            });
          }
          return acc;
        },
        [](bool a, bool b) { return a || b; });
    if (!any_fail) break;
    ++grid.fixup_rounds;
    for (int level = 1; level <= top; ++level)
      for (std::size_t c = 0; c < fail[level].size(); ++c)
        if (fail[level][c]) split[level][c] = 1;
  }
  grid.balance_seconds = seconds_since(start);

  // ---- emission: leaves level by level (coarse first), rows of cells in order ----------------
  const auto emit_start = std::chrono::steady_clock::now();
  std::vector<std::uint64_t> block_triangles(blocks.size() + 1, 0), block_leaves(blocks.size(), 0);

  // Vertex bitmap, one bit per texel, rows padded to 64-bit words.
  const std::size_t words = (static_cast<std::size_t>(w) + 63) / 64;
  std::vector<std::uint64_t> used(words * static_cast<std::size_t>(h), 0);
  const auto mark = [&](Pt p) {
    std::atomic_ref<std::uint64_t> word(used[static_cast<std::size_t>(p.y) * words + p.x / 64]);
    const std::uint64_t bit = std::uint64_t{1} << (p.x % 64);
    if ((word.load(std::memory_order_relaxed) & bit) == 0)
      word.fetch_or(bit, std::memory_order_relaxed);
  };
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, blocks.size()),
      [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
          const int level = blocks[k].level;
          std::uint64_t tris = 0, leaves = 0;
          for_each_leaf(blocks[k], [&](int i, int j) {
            const Quadtree::Box b = q.box(level, i, j);
            const unsigned config = config_of(level, i, j, b);
            ++leaves;
            tris += 2 + static_cast<unsigned>(std::popcount(config));
            mark({b.x0, b.y0}), mark({b.x1, b.y0}), mark({b.x0, b.y1}), mark({b.x1, b.y1});
            const int half = level > 0 ? 1 << (level - 1) : 0;
            if (config & kSplitTop) mark({b.x0 + half, b.y0});
            if (config & kSplitBottom) mark({b.x0 + half, b.y1});
            if (config & kSplitLeft) mark({b.x0, b.y0 + half});
            if (config & kSplitRight) mark({b.x1, b.y0 + half});
          });
          block_triangles[k + 1] = tris;
          block_leaves[k] = leaves;
        }
      });
  for (std::size_t k = 0; k < blocks.size(); ++k) {
    block_triangles[k + 1] += block_triangles[k];
    grid.leaves += block_leaves[k];
  }

  // Ranks: vertices are numbered in texel order (row-major).
  std::vector<std::uint32_t> word_rank(used.size() + 1, 0);
  for (std::size_t k = 0; k < used.size(); ++k)
    word_rank[k + 1] = word_rank[k] + static_cast<std::uint32_t>(std::popcount(used[k]));
  grid.vertices.resize(word_rank.back());
  tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
    for (int r = rows.begin(); r != rows.end(); ++r)
      for (std::size_t wd = 0; wd < words; ++wd) {
        const std::size_t k = static_cast<std::size_t>(r) * words + wd;
        std::uint32_t at = word_rank[k];
        for (std::uint64_t bits = used[k]; bits; bits &= bits - 1) {
          const int col = static_cast<int>(wd * 64) + std::countr_zero(bits);
          grid.vertices[at++] = static_cast<std::uint32_t>(r) * static_cast<std::uint32_t>(w) +
                                static_cast<std::uint32_t>(col);
        }
      }
  });
  const auto rank = [&](Pt p) {
    const std::size_t k = static_cast<std::size_t>(p.y) * words + p.x / 64;
    const std::uint64_t below = (std::uint64_t{1} << (p.x % 64)) - 1;
    return word_rank[k] + static_cast<std::uint32_t>(std::popcount(used[k] & below));
  };

  grid.indices.resize(3 * block_triangles.back());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size()),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t k = range.begin(); k != range.end(); ++k) {
                        const int level = blocks[k].level;
                        std::uint32_t* out = grid.indices.data() + 3 * block_triangles[k];
                        for_each_leaf(blocks[k], [&](int i, int j) {
                          const Quadtree::Box b = q.box(level, i, j);
                          std::array<Pt, 3> tri[6];
                          const int n = cell_triangles(b, level > 0 ? 1 << (level - 1) : 0,
                                                       config_of(level, i, j, b), tri);
                          for (int t = 0; t < n; ++t) {
                            const std::uint32_t a = rank(tri[t][0]), bb = rank(tri[t][1]),
                                                c = rank(tri[t][2]);
                            if (standard) {
                              *out++ = a, *out++ = bb, *out++ = c;
                            } else {
                              *out++ = a, *out++ = c, *out++ = bb;
                            }
                          }
                        });
                        LV_CHECK_EQ(out, grid.indices.data() + 3 * block_triangles[k + 1]);
                      }
                    });

  // Border vertices per side.
  const auto has = [&](int col, int row) {
    return (used[static_cast<std::size_t>(row) * words + col / 64] >> (col % 64)) & 1;
  };
  for (int c = 0; c < w; ++c) {
    if (has(c, 0)) grid.border[kTop].push_back(c);
    if (has(c, h - 1)) grid.border[kBottom].push_back(c);
  }
  for (int r = 0; r < h; ++r) {
    if (has(w - 1, r)) grid.border[kRight].push_back(r);
    if (has(0, r)) grid.border[kLeft].push_back(r);
  }
  grid.emit_seconds = seconds_since(emit_start);
  return grid;
}

double RefinementPyramid::measure(const AdaptiveGrid& grid) const {
  const std::uint32_t w = static_cast<std::uint32_t>(grid.width);
  const auto pt = [&](std::uint32_t v) {
    const std::uint32_t id = grid.vertices[v];
    return Pt{static_cast<int>(id % w), static_cast<int>(id / w)};
  };
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, grid.num_triangles(), 256), 0.0,
      [&](const tbb::blocked_range<std::size_t>& r, double m) {
        for (std::size_t t = r.begin(); t != r.end(); ++t)
          m = std::max(m, triangle_error(texels_, pt(grid.indices[3 * t]),
                                         pt(grid.indices[3 * t + 1]), pt(grid.indices[3 * t + 2])));
        return m;
      },
      [](double a, double b) { return std::max(a, b); });
}

}  // namespace lightvol
