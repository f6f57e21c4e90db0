// Fuzz target: the builders fed small depth arrays and lights. Static and adaptive volumes
// (spot, directional, omni) of any depths must be built and must pass the linear checks with
// their light: a failure is a builder bug, not bad input. One refusal is part of the contract:
// the float32 guard (volume/float32_guard.h) refuses, as ErrorKind::unrepresentable, volumes of a
// needle of a frustum or of far/near 1e6, which float32 cannot place within a texel. It may do so
// only for those extreme variations; the plain lights must always build.
//
// Layout: byte 0 light type and depth encoding, 1 width, 2 height, 3 adaptive max error, 4 flags
// (flip_y, light space) and the light's variation (field of view or extent, near and far range,
// direction), then one byte per texel (depth = byte / 255, in the encoding's range).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include <lightvol/check/check.h>
#include <lightvol/core/check.h>
#include <lightvol/depth/cube_faces.h>
#include <lightvol/light/light.h>
#include <lightvol/volume/adaptive_volume.h>
#include <lightvol/volume/omni_adaptive.h>
#include <lightvol/volume/omni_volume.h>
#include <lightvol/volume/static_volume.h>

namespace {

using namespace lightvol;

// `extreme`: the light is one the float32 guard may refuse (a fov of 10 degrees or ortho extents
// of 0.01 on maps of up to 16 texels, or far/near of 1e6).
void require_sound(const Result<Mesh>& mesh, const Light& light, Space space, bool extreme,
                   const char* what) {
  if (!mesh && extreme && mesh.error().kind == ErrorKind::unrepresentable) return;
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
  // Depth encoding: window, linear, or (spot, omni) radial.
  const int encoding_choice = (data[0] / 3) % 3;
  const bool linear = encoding_choice != 0;
  const bool radial = encoding_choice == 2 && type != 1;
  const int width = 2 + data[1] % 15;
  const int height = type == 2 ? width : 2 + data[2] % 15;
  const double max_error = 1.0 / static_cast<double>(1 + data[3] % 100);
  const bool flip_y = (data[4] & 1) != 0;
  const Space space = (data[4] & 2) != 0 ? Space::light : Space::world;
  // Bits 2-7 of byte 4 vary the light: 0 is the plain light of the seeds.
  const int shape = (data[4] >> 2) & 3, range = (data[4] >> 4) & 3, tilt = (data[4] >> 6) & 3;
  const bool extreme = shape == 1 || range == 1;
  static constexpr double kFov[4] = {60, 10, 120, 170};
  static constexpr double kOrthoScale[4] = {1, 0.01, 100, 1};
  static constexpr double kNear[4] = {0.1, 1e-3, 1, 0.1}, kFar[4] = {30, 1e3, 1.5, 30};
  static constexpr double kDirNear[4] = {0, 0, 2, 0}, kDirFar[4] = {10, 1e3, 2.5, 10};
  static constexpr const char* kDirection[4] = {"[0, -1, 0]", "[0.3, -1, 0.2]", "[1, 0, 0]",
                                                "[0, -1, 0]"};
  static constexpr const char* kUp[4] = {"[0, 0, -1]", "[0, 0, -1]", "[0, 1, 0]", "[0, 0, -1]"};
  const auto num = [](double x) { return std::to_string(x); };
  const std::string encoding = radial ? "radial" : linear ? "linear" : "window";
  const std::string flip = flip_y ? ", \"flip_y\": true" : "";
  const std::string frame =
      std::string(R"("direction": )") + kDirection[tilt] + R"(, "up": )" + kUp[tilt];
  std::string json;
  if (type == 0)
    json = R"({"type": "spot", "position": [0, 4, 0], )" + frame + R"(, "fov_y_deg": )" +
           num(kFov[shape]) + R"(, "aspect": )" + num(static_cast<double>(width) / height) +
           R"(, "near": )" + num(kNear[range]) + R"(, "far": )" + num(kFar[range]) +
           R"(, "depth": ")" + encoding + "\"" + flip + "}";
  else if (type == 1)
    json = R"({"type": "directional", "position": [0, 4, 0], )" + frame + R"(, "ortho": [)" +
           num(-5 * kOrthoScale[shape]) + ", " + num(5 * kOrthoScale[shape]) + ", " +
           num(-4 * kOrthoScale[shape]) + ", " + num(4 * kOrthoScale[shape]) + R"(], "near": )" +
           num(kDirNear[range]) + R"(, "far": )" + num(kDirFar[range]) + R"(, "depth": ")" +
           encoding + "\"" + flip + "}";
  else
    json = R"({"type": "omni", "position": [0, 1, 0], "near": )" + num(kNear[range]) +
           R"(, "far": )" + num(kFar[range]) + R"(, "depth": ")" + encoding + "\"" + flip + "}";
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
    require_sound(build_static_volume(*light, depth, vo, "fuzz"), *light, space, extreme, "static");
    require_sound(build_adaptive_volume(*light, depth, vo, ao, "fuzz"), *light, space, extreme,
                  "adaptive");
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
    require_sound(build_omni_volume(*light, cube, vo), *light, space, extreme, "omni static");
    require_sound(build_adaptive_omni_volume(*light, cube, vo, ao), *light, space, extreme,
                  "omni adaptive");
  }
  return 0;
}
