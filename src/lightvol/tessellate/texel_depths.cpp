// TexelDepths: the texel error metric, the window depth of every texel and the world distance
// along its ray between two window depths.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <lightvol/core/buffer.h>
#include <lightvol/core/check.h>
#include <lightvol/core/detail/block_scan.h>
#include <lightvol/light/texel.h>
#include <lightvol/tessellate/adaptive_grid.h>

namespace lightvol {

// Long (over 80 lines) on purpose: the per-texel loop converts each encoding to window depth and
// the error scale in one pass over the texels (one read of the image, written once), with the
// projection's constants set up before it.
Result<TexelDepths> TexelDepths::create(const Light& light, const DepthImage& image, int face,
                                        const std::string& source, bool borrow) {
  const int w = image.width, h = image.height;
  LV_CHECK(w >= 2 && h >= 2);
  TexelDepths t;
  t.width_ = w;
  t.height_ = h;
  const std::size_t n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);

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
  const auto xn = [w](int c) { return texel_ndc_x(c, w); };
  const auto yn = [h, &light](int r) { return texel_ndc_y(r, h, light.flip_y); };
  t.w0_dc_ = m(3, 0) * 2.0 / w;
  t.w0_dr_ = m(3, 1) * sy * 2.0 / h;
  t.w0_c_ = m(3, 0) * xn(0) + m(3, 1) * yn(0) - m(3, 2) + m(3, 3);
  t.w1_ = h1[3];
  t.uniform_ = m(3, 0) == 0 && m(3, 1) == 0 && h1[3] == 0;
  if (t.uniform_) {
    t.uniform_scale_ = std::sqrt(h1[0] * h1[0] + h1[1] * h1[1] + h1[2] * h1[2]) / std::abs(t.w0_c_);
  } else {
    t.scale_ = std::make_unique_for_overwrite<double[]>(n);
  }

  const bool window = light.depth == DepthEncoding::window;
  const Mat4d& pj = light.projection;
  const bool linear_fast = light.depth == DepthEncoding::linear && pj(2, 0) == 0 && pj(2, 1) == 0 &&
                           pj(3, 0) == 0 && pj(3, 1) == 0;
  const double pz = pj(2, 2), pzc = pj(2, 3), pw = pj(3, 2), pwc = pj(3, 3);
  // The window depth of a stored value, for the two encodings converted without unprojecting.
  const auto fast_depth = [&](double stored) {
    if (window) return std::clamp(stored, 0.0, 1.0);
    // The projection's z and w rows see only the eye depth z = −stored.
    const double z = -std::clamp(stored, light.near, light.far);
    return std::clamp(0.5 * ((pz * z + pzc) / (pw * z + pwc) + 1.0), 0.0, 1.0);
  };
  // Whether test(stored value) holds for every texel.
  const auto every_value = [&](auto test) {
    const float* values = image.values.data();
    return detail::first_failing_block(n, [&](std::size_t v) { return test(values[v]); }) == n;
  };
  // Floats when every depth is one exactly (window: always; linear: checked).
  t.float_depths_ = window;
  // Borrowed: every stored value is its own window depth.
  const bool borrowed = borrow && (window || linear_fast) &&
                        every_value([&](float v) { return fast_depth(v) == double{v}; });
  if (borrowed) {
    t.float_depths_ = true;
  } else if (linear_fast) {
    t.float_depths_ = every_value([&](float v) {
      const double d = fast_depth(v);
      return static_cast<double>(static_cast<float>(d)) == d;
    });
  }
  if (borrowed) {
    t.depth_fp_ = image.values.data();
  } else if (t.float_depths_) {
    t.depth_f_ = std::make_unique_for_overwrite<float[]>(n);
    t.depth_fp_ = t.depth_f_.get();
  } else {
    t.depth_ = std::make_unique_for_overwrite<double[]>(n);
  }
  // The error scale of a texel of row r, column c at window depth d (the formula below, term for
  // term: the same doubles whichever loop computes it).
  const auto scale_at = [&](double x, double y, double d) {
    double h0[4];
    for (int k = 0; k < 4; ++k) h0[k] = m(k, 0) * x + m(k, 1) * y - m(k, 2) + m(k, 3);
    const Vec3d g{h1[0] * h0[3] - h0[0] * h1[3], h1[1] * h0[3] - h0[1] * h1[3],
                  h1[2] * h0[3] - h0[2] * h1[3]};
    return length(g) / std::abs(h0[3] + d * h1[3]);
  };
  if (borrowed && t.uniform_) return t;  // no depth to convert, no scale to compute
  if (window || linear_fast) {
    // Row by row in two loops that vectorize (-fopenmp-simd, -fno-math-errno for the square
    // root): the depths, then the error scales from the depths just written.
    std::vector<double> xs(static_cast<std::size_t>(w));
    for (int c = 0; c < w; ++c) xs[static_cast<std::size_t>(c)] = xn(c);
    tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
      std::vector<double> d(static_cast<std::size_t>(w));
      for (int r = rows.begin(); r != rows.end(); ++r) {
        const float* in = image.values.data() + t.index(0, r);
#pragma omp simd
        for (int c = 0; c < w; ++c) d[c] = fast_depth(in[c]);
        if (borrowed) {
          // The image's floats are the depths.
        } else if (t.float_depths_) {
          float* out = t.depth_f_.get() + t.index(0, r);
#pragma omp simd
          for (int c = 0; c < w; ++c) out[c] = static_cast<float>(d[c]);
        } else {
          std::copy(d.begin(), d.end(), t.depth_.get() + t.index(0, r));
        }
        if (t.uniform_) continue;
        const double y = yn(r);
        double* k = t.scale_.get() + t.index(0, r);
#pragma omp simd
        for (int c = 0; c < w; ++c) k[c] = scale_at(xs[c], y, d[c]);
      }
    });
    return t;
  }
  const Unprojector unproject(light, w, h, face, Space::world);
  std::atomic<std::size_t> first_bad{std::numeric_limits<std::size_t>::max()};
  tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
    for (int r = rows.begin(); r != rows.end(); ++r) {
      for (int c = 0; c < w; ++c) {
        const std::size_t v = t.index(c, r);
        const double stored = image.values[v];
        double d = 0;
        if (window || linear_fast) {
          d = fast_depth(stored);
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
        if (t.float_depths_) {
          t.depth_f_[v] = static_cast<float>(d);
        } else {
          t.depth_[v] = d;
        }
        if (!t.uniform_) t.scale_[v] = scale_at(xn(c), yn(r), d);
      }
    }
  });
  if (const std::size_t bad = first_bad.load(); bad != std::numeric_limits<std::size_t>::max()) {
    return unreachable_radial_depth(source, static_cast<int>(bad % w), static_cast<int>(bad / w),
                                    image.values[bad]);
  }
  return t;
}

TexelDepths TexelDepths::with_double_depths() const {
  TexelDepths t;
  t.width_ = width_;
  t.height_ = height_;
  const std::size_t n = static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_);
  t.depth_ = std::make_unique_for_overwrite<double[]>(n);
  for (int r = 0; r < height_; ++r)
    for (int c = 0; c < width_; ++c) t.depth_[index(c, r)] = window_depth(c, r);
  if (!uniform_) {
    t.scale_ = std::make_unique_for_overwrite<double[]>(n);
    std::copy(scale_.get(), scale_.get() + n, t.scale_.get());
  }
  t.uniform_ = uniform_;
  t.uniform_scale_ = uniform_scale_;
  t.w0_c_ = w0_c_, t.w0_dc_ = w0_dc_, t.w0_dr_ = w0_dr_, t.w1_ = w1_;
  return t;
}

}  // namespace lightvol
