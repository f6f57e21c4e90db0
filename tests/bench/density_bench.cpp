// Heterogeneous media (docs/design.md §6, "Media of varying density"): the `volume` method's
// per-frame in-scattering grid and opacity map against `raymarch` (the seed's method), both
// against the CPU reference, on the analytic floor-and-box scene of the render tests with a noise
// fog. Prints the convergence of the volume method in depth slices (32 … 256) and opacity-map
// layers (16 … 128), then ray marching at growing step counts, and the time ratio at the first step
// count whose error reaches the target (and at the volume's own error, when marching reaches it).
//
//   density_bench [WIDTH HEIGHT FRAMES TARGET MAX_STEPS]   (defaults 192 144 5 0.02 2048)
//
// With LIGHTVOL_RENDER_PICTURES=DIR it also writes the reference and the default volume as PNG.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <lightvol/gl/context.h>
#include <lightvol/render/gl_marchers.h>
#include <lightvol/render/gl_volume.h>
#include <lightvol/render/image_io.h>
#include <lightvol/render/reference.h>
#include <lightvol/volume/static_volume.h>

#include "support/analytic_scene.h"
#include "support/test_support.h"

using namespace lightvol;

namespace {

template <class R>
double time_frames(R& renderer, int frames, Image* image) {
  *image = renderer.render();  // warm-up (shader JIT, uploads)
  std::vector<double> t;
  for (int i = 0; i < frames; ++i) {
    double s = 0;
    renderer.render(&s);
    t.push_back(s);
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  const int width = argc > 1 ? std::atoi(argv[1]) : 192;
  const int height = argc > 2 ? std::atoi(argv[2]) : 144;
  const int frames = argc > 3 ? std::atoi(argv[3]) : 5;
  const double target = argc > 4 ? std::atof(argv[4]) : 0.02;
  const int max_steps = argc > 5 ? std::atoi(argv[5]) : 2048;
  const char* pictures = std::getenv("LIGHTVOL_RENDER_PICTURES");
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // rows as they come, also into a file

  Result<std::unique_ptr<gl::Context>> context = gl::Context::create();
  if (!context) {
    std::fprintf(stderr, "density_bench: %s\n", context.error().message.c_str());
    return 2;
  }
  std::printf("renderer: %s, %s\n", (*context)->renderer().c_str(), (*context)->version().c_str());

  const Light light = test::light_from_json(test::spot_json("linear"));
  const int map_size = 512;
  const DepthImage map = test::scene_shadow_map(light, map_size, map_size);
  Result<Mesh> volume = build_static_volume(light, map, {}, "shadow");
  if (!volume) {
    std::fprintf(stderr, "density_bench: %s\n", volume.error().message.c_str());
    return 2;
  }
  Medium medium;
  medium.scattering = 0.15;
  medium.absorption = 0.05;
  medium.intensity = 20;
  medium.phase = {PhaseType::hg, 0.3, 0};
  medium.density.type = DensityType::noise;
  medium.density.noise.seed = 11;
  medium.density.noise.frequency = 0.6;
  medium.density.noise.octaves = 3;
  medium.density.noise.offset = 0.5;
  medium.density.noise.scale = 0.8;
  const RenderScene scene = test::make_render_scene(
      test::make_camera({7, 2, 7}, {0, 0.3, 0}, width, height, 40), light, medium);

  const auto t0 = std::chrono::steady_clock::now();
  const Image ref = render_reference(*volume, scene);
  const double ref_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf(
      "scene: spot light, %dx%d shadow map, camera %dx%d, noise fog (3 octaves, finest "
      "wavelength %.2f); CPU reference %.1f s\n\n",
      map_size, map_size, width, height, medium.density.finest_wavelength(), ref_seconds);
  std::printf("%-44s %10s %14s\n", "method", "ms/frame", "rel. L2 error");

  const auto run_volume = [&](const GlVolumeOptions& o, const std::string& name, Image* out) {
    Result<std::unique_ptr<GlVolumeRenderer>> r = GlVolumeRenderer::create(scene, o);
    if (!r) {
      std::fprintf(stderr, "density_bench: %s\n", r.error().message.c_str());
      std::exit(2);
    }
    (*r)->set_volume(*volume);
    Image image;
    const double s = time_frames(**r, frames, &image);
    const double e = compare_images(image, ref).relative_l2;
    std::printf("%-44s %10.2f %14.2e\n", name.c_str(), 1e3 * s, e);
    if (out) *out = image;
    return std::pair{1e3 * s, e};
  };
  GlVolumeOptions defaults;
  Image default_image;
  const auto [volume_ms, volume_error] =
      run_volume(defaults, "volume, defaults (128 slices, 64² x 64 layers)", &default_image);
  for (int slices : {32, 64, 128, 256}) {
    GlVolumeOptions o;
    o.density.slices = slices;
    run_volume(o, "volume, " + std::to_string(slices) + " depth slices", nullptr);
  }
  for (int layers : {16, 32, 64, 128}) {
    GlVolumeOptions o;
    o.density.opacity.layers = layers;
    run_volume(o, "volume, " + std::to_string(layers) + " opacity layers", nullptr);
  }
  for (int tile : {1, 2, 4}) {
    GlVolumeOptions o;
    o.density.tile = tile;
    run_volume(o, "volume, tile " + std::to_string(tile), nullptr);
  }
  double target_ms = 0, same_ms = 0;
  int target_n = 0, same_n = 0;
  for (int n = 16; n <= max_steps; n *= 2) {
    MarchOptions o;
    o.samples = n;
    Result<std::unique_ptr<GlMarcher>> r = GlMarcher::create(scene, {map}, {"shadow"}, o);
    if (!r) {
      std::fprintf(stderr, "density_bench: %s\n", r.error().message.c_str());
      return 2;
    }
    Image image;
    const double s = time_frames(**r, std::max(1, frames / 2), &image);
    const double e = compare_images(image, ref).relative_l2;
    std::printf("%-44s %10.2f %14.2e\n", ("raymarch N=" + std::to_string(n)).c_str(), 1e3 * s, e);
    if (target_n == 0 && e <= target) target_n = n, target_ms = 1e3 * s;
    if (same_n == 0 && e <= volume_error) same_n = n, same_ms = 1e3 * s;
    if (same_n > 0) break;
  }
  std::printf("\n");
  if (target_n > 0)
    std::printf(
        "raymarch first reaches %.2g%% at N = %d: %.2f ms against %.2f ms for the volume "
        "at its defaults (%.2e): %.1fx\n",
        100 * target, target_n, target_ms, volume_ms, volume_error, target_ms / volume_ms);
  if (same_n > 0)
    std::printf("raymarch reaches the volume's error %.2e at N = %d: %.2f ms, %.1fx the volume\n",
                volume_error, same_n, same_ms, same_ms / volume_ms);
  else
    std::printf("raymarch does not reach the volume's error %.2e within %d steps\n", volume_error,
                max_steps);
  if (pictures) {
    std::vector<double> sorted = ref.values;
    std::sort(sorted.begin(), sorted.end());
    const double p = sorted[sorted.size() * 995 / 1000];
    const double exposure = p > 0 ? 4.0 / p : 1.0;
    (void)write_image(std::string(pictures) + "/density_reference.png", ref, exposure);
    (void)write_image(std::string(pictures) + "/density_volume.png", default_image, exposure);
  }
  return 0;
}
