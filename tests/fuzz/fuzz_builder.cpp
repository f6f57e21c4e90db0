// Fuzz target: the builders fed small depth arrays and lights. Static and adaptive volumes
// (spot, directional, omni) of any depths must be built and must pass the linear checks with
// their light: a failure is a builder bug, not bad input.
//
// Layout: byte 0 light type and depth encoding, 1 width, 2 height, 3 adaptive max error, 4 flags
// (flip_y, light space), then one byte per texel (depth = byte / 255, in the encoding's range).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include <lightvol/check/check.h>
#include <lightvol/core/check.h>
#include <lightvol/depth/cube_faces.h>
#include <lightvol/light/light.h>
#include <lightvol/tessellate/adaptive_volume.h>
#include <lightvol/volume/omni_adaptive.h>
#include <lightvol/volume/omni_volume.h>
#include <lightvol/volume/static_volume.h>

namespace {

using namespace lightvol;

void require_sound(const Result<Mesh>& mesh, const Light& light, Space space, const char* what) {
  if (!mesh) {
    std::fprintf(stderr, "%s: build refused valid input: %s\n", what, mesh.error().message.c_str());
    LV_CHECK(false);
  }
  const Light frame = light_in_space(light, space);
  const CheckReport report = check_volume_linear(*mesh, &frame);
  if (!report.valid()) {
    std::fprintf(stderr, "%s: built volume fails its checks: %s\n", what,
                 report.first_failure().c_str());
    LV_CHECK(false);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 5) return 0;
  const int type = data[0] % 3;
  const bool linear = (data[0] / 3) % 2 == 1;
  const int width = 2 + data[1] % 15;
  const int height = type == 2 ? width : 2 + data[2] % 15;
  const double max_error = 1.0 / static_cast<double>(1 + data[3] % 100);
  const bool flip_y = (data[4] & 1) != 0;
  const Space space = (data[4] & 2) != 0 ? Space::light : Space::world;
  const std::string encoding = linear ? "linear" : "window";
  const std::string flip = flip_y ? ", \"flip_y\": true" : "";
  std::string json;
  if (type == 0)
    json = R"({"type": "spot", "position": [0, 4, 0], "direction": [0, -1, 0], "up": [0, 0, -1],)"
           R"( "fov_y_deg": 60, "aspect": )" + std::to_string(static_cast<double>(width) / height) +
           R"(, "near": 0.1, "far": 30, "depth": ")" + encoding + "\"" + flip + "}";
  else if (type == 1)
    json = R"({"type": "directional", "position": [0, 4, 0], "direction": [0, -1, 0],)"
           R"( "up": [0, 0, -1], "ortho": [-5, 5, -4, 4], "near": 0, "far": 10, "depth": ")" +
           encoding + "\"" + flip + "}";
  else
    json = R"({"type": "omni", "position": [0, 1, 0], "near": 0.1, "far": 10, "depth": ")" +
           encoding + "\"" + flip + "}";
  const Result<Light> light = parse_light(json, "fuzz light");
  LV_CHECK(light.ok());

  // Depths: one byte per texel, cycling through the input; linear depths span [near, far].
  const std::uint8_t* texels = data + 5;
  const std::size_t n_texels = size - 5;
  auto depth_at = [&](std::size_t i) {
    const double t = n_texels == 0 ? 1.0 : texels[i % n_texels] / 255.0;
    return static_cast<float>(linear ? light->near + t * (light->far - light->near) : t);
  };
  VolumeOptions vo;
  vo.space = space;
  AdaptiveOptions ao;
  ao.max_error = max_error;
  if (type < 2) {
    DepthImage depth;
    depth.width = width;
    depth.height = height;
    depth.values.resize(static_cast<std::size_t>(width) * height);
    for (std::size_t i = 0; i < depth.values.size(); ++i) depth.values[i] = depth_at(i);
    require_sound(build_static_volume(*light, depth, vo, "fuzz"), *light, space, "static");
    require_sound(build_adaptive_volume(*light, depth, vo, ao, "fuzz"), *light, space, "adaptive");
  } else {
    CubeFaces cube;
    std::size_t i = 0;
    for (int f = 0; f < kOmniFaces; ++f) {
      DepthImage& face = cube.faces[static_cast<std::size_t>(f)];
      face.width = face.height = width;
      face.values.resize(static_cast<std::size_t>(width) * width);
      for (float& v : face.values) v = depth_at(i++);
      cube.sources[static_cast<std::size_t>(f)] = "fuzz face " + std::to_string(f);
    }
    require_sound(build_omni_volume(*light, cube, vo), *light, space, "omni static");
    require_sound(build_adaptive_omni_volume(*light, cube, vo, ao), *light, space, "omni adaptive");
  }
  return 0;
}
