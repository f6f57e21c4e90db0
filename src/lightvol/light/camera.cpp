#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include <lightvol/core/check.h>
#include <lightvol/core/detail/json_keys.h>
#include <lightvol/light/camera.h>
#include <lightvol/light/texel.h>

namespace lightvol {
namespace {

using nlohmann::json;

}  // namespace

Result<Camera> parse_camera(std::string_view json_text, const std::string& source) {
  Result<json> root = parse_json_object(json_text, source, "a camera");
  if (!root) return root.error();
  const KeyReader keys(*root, source);
  Camera camera;
  for (auto [key, field] :
       {std::pair{"width", &camera.width}, std::pair{"height", &camera.height}}) {
    if (!keys.has(key)) return keys.error(key, "missing");
    const json& v = root->at(key);
    if (!v.is_number_integer() || v.get<long long>() < 1 || v.get<long long>() > 16384)
      return keys.error(key, "expected an integer in [1, 16384], got " + describe_json(v));
    *field = v.get<int>();
  }
  json view = *root;  // the rest is a light description
  view.erase("width");
  view.erase("height");
  if (!view.contains("type")) view["type"] = "spot";
  if (view.at("type") == "omni") return keys.error("type", "a camera cannot be an omni light");
  Result<Light> light = parse_light(view.dump(), source);
  if (!light) return light.error();
  camera.view = *light;
  return camera;
}

Result<Camera> load_camera(const std::string& path) {
  Result<std::string> text = read_text_file(path, "camera description");
  if (!text) return text.error();
  return parse_camera(*text, path);
}

// ---- camera rays --------------------------------------------------------------------------------

Ray pixel_ray(const Camera& camera, int col, int row) {
  // Pixel centre in NDC, sampled as Unprojector samples texels.
  const double x = texel_ndc_x(col, camera.width);
  const double y = texel_ndc_y(row, camera.height, camera.view.flip_y);
  bool ok = false;
  const Mat4d inv = inverse(camera.view.projection * camera.view.view, &ok);
  LV_CHECK(ok);
  const Vec3d near = inv.transform_point({x, y, -1});
  const Vec3d far = inv.transform_point({x, y, 1});
  Ray ray;
  ray.direction = normalize(far - near);
  ray.origin = camera.view.is_perspective() ? camera.view.position : near;
  return ray;
}

Result<std::vector<double>> surface_distances(const Camera& camera, const FloatBuffer& depth,
                                              int width, int height, const std::string& source) {
  if (width != camera.width || height != camera.height)
    return Error{source + ": camera depth image is " + std::to_string(width) + "x" +
                 std::to_string(height) + " but the camera is " + std::to_string(camera.width) +
                 "x" + std::to_string(camera.height)};
  LV_CHECK_EQ(depth.size(), static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  const Light& v = camera.view;
  bool ok = false;
  const Mat4d inv_p = inverse(v.projection, &ok);
  LV_CHECK(ok);
  std::vector<double> t(depth.size(), std::numeric_limits<double>::infinity());
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * width + col;
      const double d = depth[i];
      if (!std::isfinite(d) || d < 0)
        return Error{source + ": pixel (" + std::to_string(col) + ", " + std::to_string(row) +
                     "): depth " + format_number(d) + " is not a finite non-negative number"};
      const Ray ray = pixel_ray(camera, col, row);
      const bool far = (v.depth == DepthEncoding::window && d >= 1.0) ||
                       (v.depth == DepthEncoding::linear && d >= v.far);
      if (far) continue;
      if (v.depth == DepthEncoding::radial) {
        t[i] = d;  // Euclidean distance from the eye (perspective camera)
        if (d >= v.far) t[i] = std::numeric_limits<double>::infinity();
        continue;
      }
      // Window or linear depth: the point on the ray whose eye-space −z is the stored distance.
      double z_eye = d;
      if (v.depth == DepthEncoding::window) {
        z_eye = -inv_p.transform_point({0, 0, 2.0 * d - 1.0}).z;
      }
      const Vec3d dir_eye = v.view.transform_vector(ray.direction);  // rotation only
      const Vec3d origin_eye = v.view.transform_point(ray.origin);
      // −(origin_eye.z + t·dir_eye.z) = z_eye
      t[i] = (-z_eye - origin_eye.z) / dir_eye.z;
      if (t[i] < 0) t[i] = 0;
    }
  }
  return t;
}

}  // namespace lightvol
