// Builds the static volume of a 3×3 spot map through the installed library and checks its counts.
#include <cstdio>

#include <lightvol/light/light.h>
#include <lightvol/volume/static_volume.h>

int main() {
  const lightvol::Result<lightvol::Light> light = lightvol::parse_light(
      R"({"type": "spot", "position": [0, 4, 0], "direction": [0, -1, 0], "up": [0, 0, -1],
          "fov_y_deg": 60, "near": 0.1, "far": 30, "depth": "linear"})",
      "consumer");
  if (!light) return std::fprintf(stderr, "%s\n", light.error().message.c_str()), 1;
  lightvol::DepthImage depth;
  depth.width = depth.height = 3;
  depth.values.assign(9, 2.0f);
  const lightvol::Result<lightvol::Mesh> mesh =
      lightvol::build_static_volume(*light, depth, {}, "3x3");
  if (!mesh || mesh->num_triangles() != 16 || mesh->num_vertices() != 10) {
    std::fprintf(stderr, "consumer: unexpected volume\n");
    return 1;
  }
  std::printf("consumer: %zu triangles, volume %.4f\n", mesh->num_triangles(),
              lightvol::signed_volume(*mesh));
  return 0;
}
