// The in-scattering grid's columns wider than a pixel (docs/design.md §6, "Media of varying
// density"; `--grid-tile`): the `volume` method's error against the CPU reference at grid tiles 1,
// 2, 4 and 8 for three views of the analytic floor-and-box scene of the render tests with a noise
// fog: a spot seen from outside, an omni (point) light in the view near the camera, a directional
// light; against the reference on every STRIDE-th pixel of every STRIDE-th row (the reference of
// a whole image this size takes too long; STRIDE 1: all). Then, with a BIG size, the automatic
// tile at BIG×BIG the same way, and the milliseconds of one frame there.
//
//   density_tile_bench [WIDTH HEIGHT [STRIDE [BIG]]]   (defaults 512 384 8, no BIG)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <lightvol/airlight/heterogeneous.h>
#include <lightvol/gl/context.h>
#include <lightvol/render/gl_density.h>
#include <lightvol/render/gl_volume.h>
#include <lightvol/render/reference.h>
#include <lightvol/scene/bvh.h>
#include <lightvol/volume/omni_volume.h>
#include <lightvol/volume/static_volume.h>

#include "support/analytic_scene.h"
#include "support/test_support.h"

using namespace lightvol;

namespace {

struct View {
  const char* name;
  std::string light_json;
  Vec3d eye, target;
};

const View kViews[] = {
    {"spot, outside", test::spot_json("linear"), {7, 2, 7}, {0, 0.3, 0}},
    {"omni, near the camera",
     R"({"type": "omni", "position": [0.3, 2.5, 0.2], "near": 0.1, "far": 30, "depth": "linear"})",
     {2.2, 2.9, 2.0},
     {0, 1.6, 0}},
    {"directional", test::directional_json("linear"), {7, 4, 5}, {0, 0.5, 0}},
};

Medium fog() {
  Medium m;
  m.scattering = 0.15;
  m.absorption = 0.05;
  m.intensity = 20;
  m.phase = {PhaseType::hg, 0.3, 0};
  m.density.type = DensityType::noise;
  m.density.noise.seed = 11;
  m.density.noise.frequency = 0.6;
  m.density.noise.octaves = 3;
  m.density.noise.offset = 0.5;
  m.density.noise.scale = 0.8;
  return m;
}

Mesh volume_of(const Light& light) {
  Result<Mesh> v = Error{""};
  if (light.type == LightType::omni) {
    v = build_omni_volume(light, test::scene_cube_faces(light, 256), {});
  } else {
    v = build_static_volume(light, test::scene_shadow_map(light, 512, 512), {}, "shadow");
  }
  if (!v) {
    std::fprintf(stderr, "density_tile_bench: %s\n", v.error().message.c_str());
    std::exit(2);
  }
  return std::move(*v);
}

Image render_volume(const RenderScene& scene, const Mesh& volume, int tile, int* tile_used) {
  GlVolumeOptions o;
  o.density.tile = tile;
  Result<std::unique_ptr<GlVolumeRenderer>> r = GlVolumeRenderer::create(scene, o);
  if (!r) {
    std::fprintf(stderr, "density_tile_bench: %s\n", r.error().message.c_str());
    std::exit(2);
  }
  (*r)->set_volume(volume);
  if (tile_used) {
    Result<std::unique_ptr<GlDensityGrid>> grid = GlDensityGrid::create(scene, o.density);
    *tile_used = grid ? (*grid)->tile() : -1;
  }
  return (*r)->render();
}

// Milliseconds of a second frame at the automatic tile (the grid's compute passes, the volume and
// the resolve: GlVolumeRenderer::render's time; not the set-up, not the read-back).
double frame_ms(const RenderScene& scene, const Mesh& volume) {
  Result<std::unique_ptr<GlVolumeRenderer>> r = GlVolumeRenderer::create(scene, {});
  if (!r) {
    std::fprintf(stderr, "density_tile_bench: %s\n", r.error().message.c_str());
    std::exit(2);
  }
  (*r)->set_volume(volume);
  (*r)->render();
  double seconds = 0;
  (*r)->render(&seconds);
  return 1000 * seconds;
}

}  // namespace

int main(int argc, char** argv) {
  const int width = argc > 1 ? std::atoi(argv[1]) : 512;
  const int height = argc > 2 ? std::atoi(argv[2]) : 384;
  const int stride = argc > 3 ? std::atoi(argv[3]) : 8;
  const int big = argc > 4 ? std::atoi(argv[4]) : 0;
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  Result<std::unique_ptr<gl::Context>> context = gl::Context::create();
  if (!context) {
    std::fprintf(stderr, "density_tile_bench: %s\n", context.error().message.c_str());
    return 2;
  }
  // Only the sampled pixels of an image count.
  const auto sampled = [&](Image image) {
    for (std::size_t i = 0; i < image.values.size(); ++i)
      if (static_cast<int>(i / image.width) % stride != stride / 2 ||
          static_cast<int>(i % image.width) % stride != stride / 2)
        image.values[i] = 0;
    return image;
  };
  std::printf(
      "renderer: %s; %dx%d, relative L2 error vs reference on every %dth pixel of every %dth "
      "row\n\n",
      (*context)->renderer().c_str(), width, height, stride, stride);
  std::printf("| view | tile 1 | tile 2 | tile 4 | tile 8 |\n|---|---:|---:|---:|---:|\n");
  for (const View& v : kViews) {
    const Light light = test::light_from_json(v.light_json);
    const Mesh volume = volume_of(light);
    const RenderScene scene = test::make_render_scene(
        test::make_camera(v.eye, v.target, width, height, 50), light, fog());
    const Image ref = render_reference(volume, scene, stride);
    std::printf("| %s |", v.name);
    for (int tile : {1, 2, 4, 8})
      std::printf(
          " %.2e |",
          compare_images(sampled(render_volume(scene, volume, tile, nullptr)), ref).relative_l2);
    std::printf("\n");
  }
  if (big <= 0) return 0;
  std::printf(
      "\n%dx%d, automatic tile\n\n| view | tile | relative L2 | ms/frame |\n|---|---:|---:|---:|\n",
      big, big);
  for (const View& v : kViews) {
    const Light light = test::light_from_json(v.light_json);
    const Mesh volume = volume_of(light);
    const RenderScene scene =
        test::make_render_scene(test::make_camera(v.eye, v.target, big, big, 50), light, fog());
    const Image ref = render_reference(volume, scene, stride);
    int tile = 0;
    const Image gpu = sampled(render_volume(scene, volume, 0, &tile));
    std::printf("| %s | %d | %.2e | %.0f |\n", v.name, tile, compare_images(gpu, ref).relative_l2,
                frame_ms(scene, volume));
  }
  return 0;
}
