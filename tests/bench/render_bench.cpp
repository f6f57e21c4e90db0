// lightvol render's speed claim (the paper: 96 FPS for light volumes against 10 FPS for 400-step
// ray marching at equal quality). On the analytic floor-and-box scene of the render tests, at
// 1024×768 by default: time per frame of the `volume` method (static and adaptive volumes) and of
// `raymarch` at growing step counts, each with its relative L2 error against the CPU reference of
// the static volume. The camera looks at the lit floor and the box with the light just above the
// view (rays near the light are where a uniform marcher needs the most steps). Prints a table and
// the ratio at the first step count whose error reaches the target.
//
//   render_bench [WIDTH HEIGHT MAP FRAMES TARGET MAX_STEPS]   (defaults 1024 768 1024 5 0.02 1024)
//
// With LIGHTVOL_RENDER_PICTURES=DIR it also writes the images as PNG (one exposure for all) to DIR;
// LIGHTVOL_RENDER_PROFILE="INNER,OUTER" gives the spot a soft edge (degrees).
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
#include <lightvol/volume/adaptive_volume.h>
#include <lightvol/volume/static_volume.h>

#include "support/analytic_scene.h"
#include "support/test_support.h"

using namespace lightvol;

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

template <class R>
double time_frames(R& renderer, int frames, Image* image) {
  *image = renderer.render();  // warm-up (shader JIT, uploads)
  std::vector<double> t;
  for (int i = 0; i < frames; ++i) {
    double s = 0;
    renderer.render(&s);
    t.push_back(s);
  }
  return median(t);
}

const char* picture_dir = std::getenv("LIGHTVOL_RENDER_PICTURES");
double exposure = 0;

// One exposure for all images comparable with the reference; `own_exposure` for the radial blur,
// whose units are its own.
void picture(const std::string& name, const Image& image, bool own_exposure = false) {
  if (picture_dir == nullptr) return;
  const std::string path = std::string(picture_dir) + "/" + name + ".png";
  if (Status s = write_image(path, image, own_exposure ? 0.0 : exposure); !s)
    std::fprintf(stderr, "%s\n", s.error().message.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  const int width = argc > 1 ? std::atoi(argv[1]) : 1024;
  const int height = argc > 2 ? std::atoi(argv[2]) : 768;
  const int map_size = argc > 3 ? std::atoi(argv[3]) : 1024;
  const int frames = argc > 4 ? std::atoi(argv[4]) : 5;
  const double target = argc > 5 ? std::atof(argv[5]) : 0.02;
  const int max_steps = argc > 6 ? std::atoi(argv[6]) : 1024;

  Result<std::unique_ptr<gl::Context>> context = gl::Context::create();
  if (!context) {
    std::fprintf(stderr, "render_bench: %s\n", context.error().message.c_str());
    return 2;
  }
  std::printf("renderer: %s, %s\n", (*context)->renderer().c_str(), (*context)->version().c_str());

  const Light light = test::light_from_json(test::spot_json("linear"));
  const DepthImage map = test::scene_shadow_map(light, map_size, map_size);
  Result<Mesh> stat = build_static_volume(light, map, {}, "shadow");
  AdaptiveOptions ao;
  ao.max_error = 0.01;
  Result<Mesh> adaptive = build_adaptive_volume(light, map, {}, ao, "shadow");
  if (!stat || !adaptive) {
    std::fprintf(stderr, "render_bench: volume build failed\n");
    return 2;
  }
  Medium medium;
  medium.scattering = 0.06;
  medium.absorption = 0.02;
  medium.intensity = 20;
  medium.phase = {PhaseType::hg, 0.3, 0};
  if (const char* p = std::getenv("LIGHTVOL_RENDER_PROFILE"))
    std::sscanf(p, "%lf,%lf", &medium.profile.inner_deg, &medium.profile.outer_deg);
  const RenderScene scene = test::make_render_scene(
      test::make_camera({7, 2, 7}, {0, 0.3, 0}, width, height, 40), light, medium);

  const auto t0 = std::chrono::steady_clock::now();
  const Image ref = render_reference(*stat, scene);
  const double ref_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  {
    std::vector<double> sorted = ref.values;
    std::sort(sorted.begin(), sorted.end());
    const double p = sorted[sorted.size() * 995 / 1000];
    exposure = p > 0 ? 4.0 / p : 1.0;
  }
  picture("reference", ref);
  std::printf("scene: spot light, %dx%d shadow map, camera %dx%d; CPU reference %.1f s\n\n",
              map_size, map_size, width, height, ref_seconds);
  std::printf("%-34s %12s %10s %8s %14s\n", "method", "triangles", "ms/frame", "FPS",
              "rel. L2 error");

  double volume_ms = 0;
  for (auto [name, mesh] : {std::pair<const char*, const Mesh*>{"volume (static)", &*stat},
                            {"volume (adaptive, E = 0.01)", &*adaptive}}) {
    Result<std::unique_ptr<GlVolumeRenderer>> r = GlVolumeRenderer::create(scene);
    if (!r) {
      std::fprintf(stderr, "render_bench: %s\n", r.error().message.c_str());
      return 2;
    }
    (*r)->set_volume(*mesh);
    Image image;
    const double s = time_frames(**r, frames, &image);
    picture(volume_ms == 0 ? "volume_static" : "volume_adaptive", image);
    if (volume_ms == 0) volume_ms = 1e3 * s;
    std::printf("%-34s %12zu %10.2f %8.2f %14.2e\n", name, mesh->num_triangles(), 1e3 * s, 1 / s,
                compare_images(image, ref).relative_l2);
  }
  double match_ms = 0;
  int match_n = 0;
  for (int m : {1, 4}) {
    for (int n = 16; n <= (m == 1 ? max_steps : std::min(max_steps, 256)); n *= 2) {
      MarchOptions o;
      o.samples = n;
      o.interleave = m;
      Result<std::unique_ptr<GlMarcher>> r = GlMarcher::create(scene, {map}, {"shadow"}, o);
      if (!r) {
        std::fprintf(stderr, "render_bench: %s\n", r.error().message.c_str());
        return 2;
      }
      Image image;
      const double s = time_frames(**r, std::max(1, frames / 2), &image);
      const double e = compare_images(image, ref).relative_l2;
      const std::string name = "raymarch N=" + std::to_string(n) + " M=" + std::to_string(m);
      picture("raymarch_n" + std::to_string(n) + "_m" + std::to_string(m), image);
      std::printf("%-34s %12s %10.2f %8.2f %14.2e\n", name.c_str(), "-", 1e3 * s, 1 / s, e);
      if (m == 1 && match_n == 0 && e <= target) {
        match_n = n;
        match_ms = 1e3 * s;
      }
      if (e <= target / 4) break;
    }
  }
  {
    MarchOptions o;
    o.method = MarchMethod::radial;
    o.samples = 96;
    Result<std::unique_ptr<GlMarcher>> r = GlMarcher::create(scene, {}, {}, o);
    if (r) {
      Image image;
      const double s = time_frames(**r, frames, &image);
      picture("radial", image, true);
      std::printf("%-34s %12s %10.2f %8.2f %14s\n", "radial blur (96 samples)", "-", 1e3 * s, 1 / s,
                  "(approximate)");
    }
  }
  std::printf("\n");
  if (match_n > 0)
    std::printf(
        "ray marching first reaches %.2g%% relative L2 at N = %d: %.2f ms vs %.2f ms for the "
        "static volume, %.1fx slower (paper: 96 FPS vs 10 FPS, 9.6x)\n",
        100 * target, match_n, match_ms, volume_ms, match_ms / volume_ms);
  else
    std::printf("ray marching did not reach %.2g%% relative L2 within %d steps\n", 100 * target,
                max_steps);
  return 0;
}
