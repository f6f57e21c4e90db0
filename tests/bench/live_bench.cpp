// The live volume's cost per frame (render/live_volume.h): the static volume made on the GPU from
// the shadow map texture and drawn (in the volume pass's vertex stage, or in two passes through
// transform feedback; and the generation alone), against drawing the same volume prebuilt (the
// mesh `lightvol build` writes, uploaded once), and against what an engine without it would do
// every frame for a moving shadow map: build the volume on the CPU and upload it before drawing
// (the read-back of the map left out). On the analytic floor-and-box scene of the render tests (a
// spot light, the camera of render_bench), for each shadow map size. Times are medians of FRAMES
// frames of GlVolumeRenderer::render (the volume pass, the resolve pass and glFinish; not the
// read-back of the image); ratios come from the same run. Runs as it is where a GPU is present
// (EGL's device platform): the renderer line says which one ran.
//
// Then the adaptive live volume (LiveOptions::max_error) against the static one: generation alone
// and whole frames, and their ratios.
//
//   live_bench [WIDTH HEIGHT FRAMES MAP...]   (defaults 1024 768 5 1024 2048)
//   LIVE_BENCH_ADAPTIVE_ONLY=1 live_bench ...  (the adaptive table only)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include <lightvol/gl/context.h>
#include <lightvol/render/gl_volume.h>
#include <lightvol/render/live_volume.h>
#include <lightvol/volume/static_volume.h>

#include "support/analytic_scene.h"
#include "support/test_support.h"

using namespace lightvol;

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

// The bound of the adaptive rows (the Sponza table's adaptive E, docs/performance.md).
constexpr double kAdaptiveError = 0.01;

int main(int argc, char** argv) {
  const int width = argc > 1 ? std::atoi(argv[1]) : 1024;
  const int height = argc > 2 ? std::atoi(argv[2]) : 768;
  const int frames = std::max(1, argc > 3 ? std::atoi(argv[3]) : 5);
  std::vector<int> maps;
  for (int i = 4; i < argc; ++i) maps.push_back(std::atoi(argv[i]));
  if (maps.empty()) maps = {1024, 2048};

  Result<std::unique_ptr<gl::Context>> context = gl::Context::create();
  if (!context) {
    std::fprintf(stderr, "live_bench: %s\n", context.error().message.c_str());
    return 2;
  }
  std::printf("renderer: %s, %s (EGL %s)\n", (*context)->renderer().c_str(),
              (*context)->version().c_str(), (*context)->platform().c_str());
  std::printf("scene: spot light (linear depth), camera %dx%d, median of %d rounds\n\n", width,
              height, frames);
  std::printf("%-5s %9s | %8s %6s | %8s %6s | %8s | %8s %6s | %8s | %8s %8s %8s | %8s\n", "map",
              "triangles", "live ms", "FPS", "2-pass", "FPS", "generate", "prebuilt", "FPS",
              "CPU+upl.", "live/pre", "2p/pre", "CPU/live", "rel. L2");

  const Light light = test::light_from_json(test::spot_json("linear"));
  Medium medium;
  medium.scattering = 0.06;
  medium.absorption = 0.02;
  medium.intensity = 20;
  medium.phase = {PhaseType::hg, 0.3, 0};
  const RenderScene scene = test::make_render_scene(
      test::make_camera({7, 2, 7}, {0, 0.3, 0}, width, height, 40), light, medium);

  const auto fail = [](const std::string& message) {
    std::fprintf(stderr, "live_bench: %s\n", message.c_str());
    return 2;
  };
  // LIVE_BENCH_ADAPTIVE_ONLY=1: the adaptive table only (the first one builds on the CPU).
  const char* adaptive_only = std::getenv("LIVE_BENCH_ADAPTIVE_ONLY");
  for (const int size : maps) {
    if (adaptive_only && std::string(adaptive_only) == "1") break;
    const DepthImage map = test::scene_shadow_map(light, size, size);
    // One renderer per way of drawing, so that each round draws all of them back to back.
    std::unique_ptr<GlVolumeRenderer> renderers[3];
    for (auto& r : renderers) {
      Result<std::unique_ptr<GlVolumeRenderer>> made = GlVolumeRenderer::create(scene);
      if (!made) return fail(made.error().message);
      r = std::move(*made);
    }
    GlVolumeRenderer &prebuilt = *renderers[0], &live_draw = *renderers[1],
                     &two_pass_draw = *renderers[2];
    Result<Mesh> mesh = build_static_volume(light, map, {}, "shadow");
    if (!mesh) return fail(mesh.error().message);
    prebuilt.set_volume(*mesh);
    // The live volume: the map uploaded once as a texture (an engine's depth pass writes it).
    const gl::TextureHandle texture = upload_shadow_map(light, map);
    Result<std::unique_ptr<LiveVolume>> live =
        LiveVolume::create(light, {texture.id(), size, size});
    if (!live) return fail(live.error().message);
    if (Status s = live_draw.set_volume(**live, LiveDraw::vertex_stage); !s)
      return fail(s.error().message);
    if (Status s = two_pass_draw.set_volume(**live, LiveDraw::two_pass); !s)
      return fail(s.error().message);
    // Warm-up frames (shader compilation, uploads), kept for the images' comparison.
    const Image prebuilt_image = prebuilt.render(), live_image = live_draw.render(),
                two_pass_image = two_pass_draw.render();

    // Rounds: each draws every way once, so that a change of load hits them alike; ratios are
    // the medians of the rounds' ratios.
    std::vector<double> t_pre, t_live, t_two, t_gen, t_cpu, live_ratio, two_ratio, cpu_ratio;
    for (int i = 0; i < frames; ++i) {
      double a = 0, b = 0, c = 0;
      prebuilt.render(&a);
      live_draw.render(&b);
      two_pass_draw.render(&c);
      // The generation alone (the paper's "tessellate" row): the two-pass way's first pass.
      auto start = std::chrono::steady_clock::now();
      (*live)->generate();
      gl::glFinish();
      t_gen.push_back(seconds_since(start));
      // What a frame costs an engine without the live volume: build on the CPU, upload, draw.
      start = std::chrono::steady_clock::now();
      Result<Mesh> rebuilt = build_static_volume(light, map, {}, "shadow");
      if (!rebuilt) return fail(rebuilt.error().message);
      prebuilt.set_volume(*rebuilt);
      const double cpu = seconds_since(start) + a;
      t_pre.push_back(a), t_live.push_back(b), t_two.push_back(c), t_cpu.push_back(cpu);
      live_ratio.push_back(b / a), two_ratio.push_back(c / a), cpu_ratio.push_back(cpu / b);
    }
    const double pre = median(t_pre), live_s = median(t_live), two = median(t_two);
    std::printf(
        "%-5d %9zu | %8.1f %6.3f | %8.1f %6.3f | %8.1f | %8.1f %6.3f | %8.1f | %8.2f %8.2f %8.2f | "
        "%8.1e\n",
        size, mesh->num_triangles(), 1e3 * live_s, 1 / live_s, 1e3 * two, 1 / two,
        1e3 * median(t_gen), 1e3 * pre, 1 / pre, 1e3 * median(t_cpu), median(live_ratio),
        median(two_ratio), median(cpu_ratio),
        std::max(compare_images(live_image, prebuilt_image).relative_l2,
                 compare_images(two_pass_image, prebuilt_image).relative_l2));
    std::fflush(stdout);
  }
  // The adaptive live volume against the static one (both two passes: generate, then draw).
  std::printf("\nadaptive, E = %g (LiveOptions::max_error; the Sponza table's adaptive bound)\n",
              kAdaptiveError);
  std::printf("%-5s %9s %9s | %8s %8s | %8s %8s | %8s %8s | %8s\n", "map", "static", "adaptive",
              "gen st", "gen ad", "frame st", "frame ad", "gen a/s", "frame a/s", "rel. L2");
  for (const int size : maps) {
    const DepthImage map = test::scene_shadow_map(light, size, size);
    const gl::TextureHandle texture = upload_shadow_map(light, map);
    Result<std::unique_ptr<LiveVolume>> live_static =
        LiveVolume::create(light, {texture.id(), size, size});
    if (!live_static) return fail(live_static.error().message);
    LiveOptions options;
    options.max_error = kAdaptiveError;
    Result<std::unique_ptr<LiveVolume>> live_adaptive =
        LiveVolume::create(light, {texture.id(), size, size}, options);
    if (!live_adaptive) return fail(live_adaptive.error().message);
    std::unique_ptr<GlVolumeRenderer> renderers[2];
    for (auto& r : renderers) {
      Result<std::unique_ptr<GlVolumeRenderer>> made = GlVolumeRenderer::create(scene);
      if (!made) return fail(made.error().message);
      r = std::move(*made);
    }
    if (Status s = renderers[0]->set_volume(**live_static); !s) return fail(s.error().message);
    if (Status s = renderers[1]->set_volume(**live_adaptive); !s) return fail(s.error().message);
    const Image static_image = renderers[0]->render(), adaptive_image = renderers[1]->render();
    Result<LiveMesh> made = (*live_adaptive)->read_mesh();  // once, outside the timed rounds
    if (!made) return fail(made.error().message);
    std::vector<double> gen_s, gen_a, frame_s, frame_a, gen_ratio, frame_ratio;
    for (int i = 0; i < frames; ++i) {
      double a = 0, b = 0;
      renderers[0]->render(&a);
      renderers[1]->render(&b);
      auto start = std::chrono::steady_clock::now();
      (*live_static)->generate();
      gl::glFinish();
      const double gs = seconds_since(start);
      start = std::chrono::steady_clock::now();
      (*live_adaptive)->generate();
      gl::glFinish();
      const double ga = seconds_since(start);
      gen_s.push_back(gs), gen_a.push_back(ga), frame_s.push_back(a), frame_a.push_back(b);
      gen_ratio.push_back(ga / gs), frame_ratio.push_back(b / a);
    }
    std::printf("%-5d %9llu %9zu | %8.1f %8.1f | %8.1f %8.1f | %8.2f %8.2f | %8.1e\n", size,
                static_cast<unsigned long long>((*live_static)->num_triangles()),
                made->mesh.num_triangles(), 1e3 * median(gen_s), 1e3 * median(gen_a),
                1e3 * median(frame_s), 1e3 * median(frame_a), median(gen_ratio),
                median(frame_ratio), compare_images(adaptive_image, static_image).relative_l2);
    std::fflush(stdout);
  }
  std::printf(
      "\nms per frame (FPS): live, the volume made from the shadow map texture in the volume "
      "pass's vertex stage and drawn (LiveDraw::vertex_stage); 2-pass, made once per vertex by "
      "transform feedback, then drawn as a mesh (LiveDraw::two_pass); generate, that first pass "
      "alone; prebuilt, build's mesh drawn from buffers uploaded once; CPU+upl., "
      "build_static_volume, the upload and the prebuilt draw. rel. L2: the larger of the two live "
      "images' differences from the prebuilt one. Adaptive table: gen st / gen ad, the static and "
      "adaptive live volumes' generation alone; frame st / frame ad, generation, volume pass and "
      "resolve; a/s, adaptive over static (median of the rounds' ratios); rel. L2, the adaptive "
      "image against the static one.\n");
  return 0;
}
