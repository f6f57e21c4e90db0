// The error kernels: the largest texel error over a triangle of the lattice or an unsplit cell,
// row by row (the inner loops vectorize: -fopenmp-simd).
#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <lightvol/core/check.h>
#include <lightvol/tessellate/detail/lattice.h>
#include <lightvol/tessellate/detail/plane_error.h>

namespace lightvol::detail {
namespace {

// A row kernel's largest error in world units (with kUniform the kernels leave out the uniform
// scale until the end).
template <bool kUniform>
double scaled(const TexelDepths& t, double worst) {
  if constexpr (kUniform) return worst * t.uniform_scale();
  return worst;
}

// The largest error over the texels (lattice points) of the closed triangle (a, b, c), rows
// [y_begin, y_end) only. The triangle's window depth is the plane through its corners' depths:
// exactly what the emitted flat triangle gives along each texel ray.
template <bool kUniform, class D>
double triangle_error_rows(const TexelDepths& t, Pt a, Pt b, Pt c, int y_begin, int y_end) {
  const TrianglePlane plane = triangle_plane(t, a, b, c);
  double worst = 0;
  for (int y = y_begin; y < y_end; ++y) {
    int x0 = 0, x1 = 0;
    if (!triangle_row_span(plane.v, y, &x0, &x1)) continue;
    worst = std::max(worst, span_error<kUniform, D>(t, y, x0, x1, plane.at(x0, y), plane.gx));
  }
  return scaled<kUniform>(t, worst);
}

// One span of a row of box_error_rows_t with the per-texel error scale: raises `m` to the largest
// error over texels [x0, x1] of the plane whose depth is base + gx·(x − xr), and with kGap `g` to
// the largest |plane − depth| (window depth, unscaled).
template <bool kGap, class D>
void scaled_span(const TexelDepths& t, const D* dt, int y, int x0, int x1, int xr, double base,
                 double gx, double& m, double& g) {
  const double* k = t.scale_row(y);
  const double w1 = t.w1();
  const double w0y = t.w0(0, y), w0dc = t.w0_dc();
  double mm = m, gg = g;
#pragma omp simd reduction(max : mm, gg)
  for (int x = x0; x <= x1; ++x) {
    const double d = base + gx * (x - xr);
    const double a = std::abs(d - dt[x]);
    const double e = a * k[x] / std::abs(w0y + w0dc * x + d * w1);
    mm = mm > e ? mm : e;
    if constexpr (kGap) gg = gg > a ? gg : a;
  }
  m = mm;
  g = gg;
}

// The two planes of an unsplit cell `b` (cell_triangles(config 0)): the upper-left triangle
// (a, b, c), whose depth is a + g1·(p − a), and the lower-right one (b, d, c), d + g2·(p − d).
struct CellPlanes {
  double da, dd, g1x, g1y, g2x, g2y;
};

// The planes of cell `b`, wx × wy texels. Inlined, so that with sides known at compile time (powers
// of two) the divisions become multiplications by their reciprocals (exact: the same quotients).
[[gnu::always_inline]] inline CellPlanes cell_planes(const TexelDepths& t, const Quadtree::Box& b,
                                                     int wx, int wy) {
  const double da = t.window_depth(b.x0, b.y0), db = t.window_depth(b.x1, b.y0),
               dc = t.window_depth(b.x0, b.y1), dd = t.window_depth(b.x1, b.y1);
  return {da, dd, (db - da) / wx, (dc - da) / wy, (dd - dc) / wx, (dd - db) / wy};
}

// Rows [y_begin, y_end) of an unsplit cell, row by row: raises `worst` to the largest error
// (with kUniform before the uniform scale) and `gap` to the largest |plane − depth| (window depth;
// with kUniform the same as `worst`; otherwise only with `with_gap`), and stops after the first
// row that takes the error past `cap`. Each texel is taken once; on the diagonal both planes
// agree.
template <bool kUniform, class D>
void box_rows_by_row(const TexelDepths& t, const Quadtree::Box& b, const CellPlanes& p, int y_begin,
                     int y_end, double cap, bool with_gap, double& worst, double& gap) {
  const int wx = b.x1 - b.x0, wy = b.y1 - b.y0;
  for (int y = y_begin; y < y_end; ++y) {
    const int s = y - b.y0;
    const int xs =
        b.x0 + (wx == wy ? wy - s : static_cast<int>((std::int64_t{wx} * (wy - s)) / wy));
    const D* dt = t.depth_row_as<D>(y);
    const double base1 = p.da + p.g1y * s, base2 = p.dd + p.g2y * (y - b.y1);
    double m = 0;
    if constexpr (kUniform) {
#pragma omp simd reduction(max : m)
      for (int x = b.x0; x <= xs; ++x) {
        const double e = std::abs(base1 + p.g1x * (x - b.x0) - dt[x]);
        m = m > e ? m : e;
      }
#pragma omp simd reduction(max : m)
      for (int x = xs + 1; x <= b.x1; ++x) {
        const double e = std::abs(base2 + p.g2x * (x - b.x1) - dt[x]);
        m = m > e ? m : e;
      }
    } else if (!with_gap) {
      scaled_span<false>(t, dt, y, b.x0, xs, b.x0, base1, p.g1x, m, gap);
      scaled_span<false>(t, dt, y, xs + 1, b.x1, b.x1, base2, p.g2x, m, gap);
    } else {  // the same, and the largest |d − depth| in window units
      scaled_span<true>(t, dt, y, b.x0, xs, b.x0, base1, p.g1x, m, gap);
      scaled_span<true>(t, dt, y, xs + 1, b.x1, b.x1, base2, p.g2x, m, gap);
    }
    if constexpr (kUniform) gap = std::max(gap, m);
    worst = std::max(worst, m);
    // Scaling is monotonic: the rows left can only raise what is already past the cap.
    if (scaled<kUniform>(t, worst) > cap) break;
  }
}

// box_rows_by_row for a whole square cell of side kSide (4, 8 or 16 texels: levels 2 to 4, whose
// short rows cost box_rows_by_row more in loop overhead and a horizontal max per row than in
// arithmetic), without its two short vectorized loops per row: one loop a row over
// its kSide + 1 texels (a count known at compile time), each texel on its own plane by a select
// (the same operations on the same operands as box_rows_by_row), raising a per-column maximum
// kept across the rows; the columns are joined only at the end, or where the cap may have been
// passed. `near` is below every error (before the uniform scale) that passes the cap, so a row
// whose columns all stay at or below it cannot pass it; a row with a column above it has its
// columns joined and the cap tested exactly as box_rows_by_row does (max and scaling commute:
// scaling is monotonic), and stops the rows at the same row. So `worst` and `gap` end as
// box_rows_by_row leaves them (kGap: the gap, non-uniform only).
template <int kSide, bool kUniform, bool kGap, class D>
void square_box_rows(const TexelDepths& t, const Quadtree::Box& b, int y_begin, int y_end,
                     double cap, double near, double& worst, double& gap) {
  constexpr int kTexels = kSide + 1;
  const CellPlanes p = cell_planes(t, b, kSide, kSide);
  const double g1x = p.g1x, g2x = p.g2x;
  double m[kTexels] = {}, g[kTexels] = {};
  const auto joined = [&] {
    double w = 0;
    for (int c = 0; c < kTexels; ++c) w = std::max(w, m[c]);
    return w;
  };
  // Row b.y0 + s (columns 0..kSide − s on the upper-left plane); true: the cap is passed.
  const auto row = [&](int s) {
    const int y = b.y0 + s, cs = kSide - s;
    const D* dt = t.depth_row_as<D>(y) + b.x0;
    const double base1 = p.da + p.g1y * s, base2 = p.dd + p.g2y * (y - b.y1);
    // Column c's depth on its plane. The select picks the plane's operands, not its computed
    // depths: GCC vectorizes a select of values, but not one of two computations it may sink into
    // branches (-ftrapping-math).
    const auto plane_depth = [&](int c) {
      const bool upper = c <= cs;
      const double base = upper ? base1 : base2, gx = upper ? g1x : g2x;
      return base + gx * (c - (upper ? 0 : kSide));
    };
    if constexpr (kUniform) {
#pragma omp simd
      for (int c = 0; c < kTexels; ++c) {
        const double e = std::abs(plane_depth(c) - dt[c]);
        m[c] = m[c] > e ? m[c] : e;
      }
    } else {
      const double* k = t.scale_row(y) + b.x0;
      const double w1 = t.w1();
      const double w0y = t.w0(0, y), w0dc = t.w0_dc();
#pragma omp simd
      for (int c = 0; c < kTexels; ++c) {
        const double d = plane_depth(c);
        const double a = std::abs(d - dt[c]);
        const double e = a * k[c] / std::abs(w0y + w0dc * (b.x0 + c) + d * w1);
        m[c] = m[c] > e ? m[c] : e;
        if constexpr (kGap) g[c] = g[c] > a ? g[c] : a;
      }
    }
    bool above = false;
    for (int c = 0; c < kTexels; ++c) above |= m[c] > near;
    return above && scaled<kUniform>(t, std::max(worst, joined())) > cap;
  };
  if (kSide <= 8 && y_begin == b.y0 && y_end == b.y1 + 1) {
    // The whole cell: a row count known at compile time, the rows unrolled.
#pragma GCC unroll 9
    for (int s = 0; s <= kSide; ++s)
      if (row(s)) break;
  } else {
    for (int s = y_begin - b.y0; s < y_end - b.y0; ++s)
      if (row(s)) break;
  }
  worst = std::max(worst, joined());
  if constexpr (kUniform) gap = std::max(gap, worst);
  if constexpr (kGap) {
    for (int c = 0; c < kTexels; ++c) gap = std::max(gap, g[c]);
  }
}

// square_box_rows' `near` for a cap: without a uniform scale, the cap; with one, s, an error w at
// or below which w·s does not round above the cap: cap / s less a relative 1e-12 (w·s rounds above
// the cap only if w > cap / s · (1 − 2⁻⁵²), when nothing underflows), 0 where cap / s is tiny or 0
// (no cap passed by 0), −∞ for a negative cap (passed by every row).
double near_cap(const TexelDepths& t, double cap) {
  if (!t.uniform()) return cap;
  const double q = cap / t.uniform_scale();
  if (q >= 1e-290) return q * (1 - 1e-12);
  return cap < 0 ? -std::numeric_limits<double>::infinity() : 0.0;
}

// The largest error over the texels of an unsplit cell (rows [y_begin, y_end)): the upper-left
// triangle (a, b, c) and the lower-right one (b, d, c) of cell_triangles(config 0), without the
// general triangle's span arithmetic. Whole square cells of 4, 8 and 16 texels a side take
// square_box_rows; the others (long rows, where its per-column maxima in memory cost more than
// they save, and cells clipped at the border) box_rows_by_row.
template <bool kUniform, class D>
double box_error_rows_t(const TexelDepths& t, const Quadtree::Box& b, int y_begin, int y_end,
                        double cap, double* depth_gap) {
  const int wx = b.x1 - b.x0, wy = b.y1 - b.y0;
  double worst = 0, gap = 0;
  const auto square = [&](auto side) {
    constexpr int kSide = decltype(side)::value;
    if (!kUniform && depth_gap != nullptr) {
      square_box_rows<kSide, kUniform, true, D>(t, b, y_begin, y_end, cap, near_cap(t, cap), worst,
                                                gap);
    } else {
      square_box_rows<kSide, kUniform, false, D>(t, b, y_begin, y_end, cap, near_cap(t, cap), worst,
                                                 gap);
    }
  };
  switch (wx == wy ? wx : 0) {
    case 4:
      square(std::integral_constant<int, 4>{});
      break;
    case 8:
      square(std::integral_constant<int, 8>{});
      break;
    case 16:
      square(std::integral_constant<int, 16>{});
      break;
    default:
      box_rows_by_row<kUniform, D>(t, b, cell_planes(t, b, wx, wy), y_begin, y_end, cap,
                                   depth_gap != nullptr, worst, gap);
  }
  if (depth_gap != nullptr) *depth_gap = gap;
  return scaled<kUniform>(t, worst);
}

}  // namespace

double triangle_error(const TexelDepths& t, Pt a, Pt b, Pt c) {
  const int y0 = std::min({a.y, b.y, c.y}), y1 = std::max({a.y, b.y, c.y}) + 1;
  const int x0 = std::min({a.x, b.x, c.x}), x1 = std::max({a.x, b.x, c.x}) + 1;
  const auto rows = [&](int ya, int yb) {
    return with_texel_kind(t, [&](auto uniform, auto depth) {
      return triangle_error_rows<decltype(uniform)::value, decltype(depth)>(t, a, b, c, ya, yb);
    });
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

double box_error_rows(const TexelDepths& t, const Quadtree::Box& b, int y_begin, int y_end,
                      double cap, double* depth_gap) {
  return with_texel_kind(t, [&](auto uniform, auto depth) {
    return box_error_rows_t<decltype(uniform)::value, decltype(depth)>(t, b, y_begin, y_end, cap,
                                                                       depth_gap);
  });
}

}  // namespace lightvol::detail
