// A lattice triangle's plane and the error of a row of texels against a plane: the kernels the
// adaptive tessellations' error measures share (error_kernels.cpp, collapse_grid.cpp). Include it
// only from files compiled with -fopenmp-simd (src/CMakeLists.txt): the loops vectorize there.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <type_traits>

#include <lightvol/core/check.h>
#include <lightvol/tessellate/adaptive_grid.h>
#include <lightvol/tessellate/detail/lattice.h>

namespace lightvol::detail {

// A lattice triangle's plane in window depth, through its corners' depths: the corners
// counter-clockwise in texel space (b and c swapped if they were not), the depth at v[0] and the
// gradient. Exactly what the emitted flat triangle gives along each texel ray.
struct TrianglePlane {
  Pt v[3];
  double d0 = 0, gx = 0, gy = 0;
  // The plane's depth at texel (x, y).
  double at(int x, int y) const { return d0 + gy * (y - v[0].y) + gx * (x - v[0].x); }
};

inline TrianglePlane triangle_plane(const TexelDepths& t, Pt a, Pt b, Pt c) {
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
  TrianglePlane p{{a, b, c}, da, 0, 0};
  p.gx = ((db - da) * (c.y - a.y) - (dc - da) * (b.y - a.y)) * inv;
  p.gy = ((dc - da) * (b.x - a.x) - (db - da) * (c.x - a.x)) * inv;
  return p;
}

// The largest error over texels [x0, x1] of row y against a plane whose depth is `base` at x0 and
// changes by `gx` a texel (TexelDepths::error; with kUniform, before the uniform scale). D is the
// type the depths are held in (TexelDepths::float_depths). The inner loops vectorize
// (-fopenmp-simd in the files that use it).
template <bool kUniform, class D>
double span_error(const TexelDepths& t, int y, int x0, int x1, double base, double gx) {
  const D* dt = t.depth_row_as<D>(y);
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
  return m;
}

// Calls f(std::bool_constant<uniform>, D{}) with the texels' kind of projection and depth type.
template <class F>
decltype(auto) with_texel_kind(const TexelDepths& t, F&& f) {
  if (t.uniform()) {
    return t.float_depths() ? f(std::true_type{}, float{}) : f(std::true_type{}, double{});
  }
  return t.float_depths() ? f(std::false_type{}, float{}) : f(std::false_type{}, double{});
}

}  // namespace lightvol::detail
