#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#include <lightvol/core/check.h>
#include <lightvol/io/mesh_reader.h>
#include <lightvol/light/texel.h>
#include <lightvol/scene/scene.h>

namespace lightvol {

Result<Mesh> load_scene(const std::string& path) {
  Result<Mesh> mesh = read_mesh(path);
  if (!mesh) return mesh;
  for (std::size_t i = 0; i < mesh->positions.size(); ++i)
    if (!std::isfinite(mesh->positions[i]))
      return Error{path + ": vertex " + std::to_string(i / 3) + " has a non-finite coordinate"};
  return mesh;
}

Result<MapSize> shadow_map_size(const Light& light, int n, const std::string& source) {
  constexpr int kMax = 16384;
  if (n < 2 || n > kMax)
    return Error{"shadow_map_size(n): must lie in [2, " + std::to_string(kMax) + "], got " +
                 std::to_string(n)};
  MapSize size{n, n};
  if (light.type == LightType::spot) {
    // The projection's aspect is width / height: P(0,0) = P(1,1) / aspect.
    const double aspect = light.projection(1, 1) / light.projection(0, 0);
    const double h = std::round(n / aspect);
    if (!(h >= 2 && h <= kMax))
      return Error{source + ": key 'aspect': width " + std::to_string(n) +
                   " (shadow_map_size(n)) gives a map " + std::to_string(h) +
                   " high; the height must lie in [2, " + std::to_string(kMax) + "]"};
    size.height = static_cast<int>(h);
  }
  return size;
}

Mat4d pass_view(const Light& light, int face) {
  return light.type == LightType::omni ? omni_face_view(light, face) : light.view;
}

namespace {

template <class T>
DepthImage encode(const Light& light, int width, int height, const std::vector<T>& window) {
  LV_CHECK(width > 0 && height > 0);
  LV_CHECK_EQ(window.size(), static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  DepthImage out;
  out.width = width;
  out.height = height;
  out.values.resize(window.size());
  if (light.depth == DepthEncoding::window) {
    for (std::size_t i = 0; i < window.size(); ++i)
      out.values[i] = static_cast<float>(std::min<double>(window[i], 1.0));
    return out;
  }
  bool ok = false;
  const Mat4d inv_projection = inverse(light.projection, &ok);
  LV_CHECK(ok);
  for (int row = 0; row < height; ++row) {
    const double y = texel_ndc_y(row, height, light.flip_y);
    for (int col = 0; col < width; ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * width + col;
      const double x = texel_ndc_x(col, width);
      const double d = std::clamp(static_cast<double>(window[i]), 0.0, 1.0);
      const Vec3d p = inv_projection.transform_point({x, y, 2 * d - 1});
      double value = light.depth == DepthEncoding::linear ? -p.z : length(p);
      if (d >= 1.0) {
        // Round away from the light so that the stored float still reads as the far plane.
        const float f = static_cast<float>(value);
        value = static_cast<double>(f) < value
                    ? std::nextafter(f, std::numeric_limits<float>::max())
                    : f;
      }
      out.values[i] = static_cast<float>(value);
    }
  }
  return out;
}

}  // namespace

DepthImage encode_depth(const Light& light, int width, int height,
                        const std::vector<double>& window) {
  return encode(light, width, height, window);
}

DepthImage encode_depth(const Light& light, int width, int height,
                        const std::vector<float>& window) {
  return encode(light, width, height, window);
}

DepthImage depth_preview(const Light& light, int width, int height,
                         const std::vector<std::vector<float>>& passes) {
  const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  DepthImage out;
  out.width = width;
  out.height = height * static_cast<int>(passes.size());
  out.values.assign(n * passes.size(), 0.0f);
  bool ok = false;
  const Mat4d inv_projection = inverse(light.projection, &ok);
  LV_CHECK(ok);
  // −z_eye of window depth d on the view axis (the projections here map it independently of x, y).
  const auto eye_depth = [&](double d) {
    return -inv_projection.transform_point({0, 0, 2 * d - 1}).z;
  };
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const std::vector<float>& pass : passes) {
    LV_CHECK_EQ(pass.size(), n);
    for (const float d : pass)
      if (d < 1.0f) {
        lo = std::min(lo, eye_depth(d));
        hi = std::max(hi, eye_depth(d));
      }
  }
  const double range = hi > lo ? hi - lo : 1.0;
  for (std::size_t p = 0; p < passes.size(); ++p)
    for (std::size_t i = 0; i < n; ++i) {
      const float d = passes[p][i];
      if (d < 1.0f)
        out.values[p * n + i] = static_cast<float>(1.0 - 0.9 * (eye_depth(d) - lo) / range);
    }
  return out;
}

}  // namespace lightvol
