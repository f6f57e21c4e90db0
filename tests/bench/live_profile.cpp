// Where the adaptive live volume's generation goes: GPU time (GL_TIME_ELAPSED) per phase and
// compute pass of shaders/live_adaptive.comp, for the shadow maps given (one for a spot or
// directional light, six faces for an omni light; e.g. made by `lightvol shadowmap`), and the
// wall time between glFinish calls around each command (llvmpipe's queries miss its compute
// dispatches, which it runs on the CPU), next to the generation's wall time unprofiled
// (LiveVolume::generate + glFinish, median of the frames).
//
//   live_profile LIGHT.json MAX_ERROR FRAMES MAP...
//   LIVE_PROFILE_ROUNDS=N live_profile ...   (LiveOptions::max_rounds, default 32)
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <memory>
#include <string>
#include <vector>

#include <lightvol/depth/shadow_maps.h>
#include <lightvol/gl/context.h>
#include <lightvol/render/live_adaptive.h>
#include <lightvol/render/live_volume.h>

using namespace lightvol;

namespace {

int fail(const std::string& message) {
  std::fprintf(stderr, "live_profile: %s\n", message.c_str());
  return 2;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5) return fail("usage: live_profile LIGHT.json MAX_ERROR FRAMES MAP...");
  const double max_error = std::atof(argv[2]);
  const int frames = std::max(1, std::atoi(argv[3]));
  Result<std::unique_ptr<gl::Context>> context = gl::Context::create();
  if (!context) return fail(context.error().message);
  Result<Light> light = load_light(argv[1]);
  if (!light) return fail(light.error().message);
  Result<ShadowMaps> maps =
      read_shadow_maps(*light, std::vector<std::string>(argv + 4, argv + argc), {});
  if (!maps) return fail(maps.error().message);
  std::vector<gl::TextureHandle> textures;
  std::vector<GlShadowMap> on_gpu;
  for (const DepthImage& map : maps->images()) {
    textures.push_back(upload_shadow_map(*light, map));
    on_gpu.push_back({textures.back().id(), map.width, map.height});
  }
  LiveOptions options;
  options.max_error = max_error;
  if (const char* rounds = std::getenv("LIVE_PROFILE_ROUNDS"))
    options.max_rounds = std::atoi(rounds);
  Result<std::unique_ptr<LiveVolume>> live = LiveVolume::create(*light, on_gpu, options);
  if (!live) return fail(live.error().message);
  // The same passes, profiled, bound as LiveVolume binds its own.
  Result<std::unique_ptr<detail::LiveAdaptive>> passes =
      detail::LiveAdaptive::create(max_error, options.max_rounds, options.max_seam_rounds);
  if (!passes) return fail(passes.error().message);
  if (Status s = (*passes)->resize(*light, on_gpu[0].width, on_gpu[0].height); !s)
    return fail(s.error().message);
  const auto bind = [&](const gl::Program& program) { (*live)->bind(program, 2); };

  Result<LiveMesh> mesh = (*live)->read_mesh();  // also the warm-up
  if (!mesh) return fail(mesh.error().message);
  std::vector<double> wall, cpu;
  for (int i = 0; i < frames; ++i) {
    const auto start = std::chrono::steady_clock::now();
    const std::clock_t cpu_start = std::clock();
    (*live)->generate();
    gl::glFinish();
    wall.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    cpu.push_back(static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC);
  }
  (*passes)->generate(bind);  // warm-up
  gl::glFinish();
  (*passes)->set_profiling(true);
  for (int i = 0; i < frames; ++i) (*passes)->generate(bind);
  const std::vector<detail::LiveAdaptive::PassTime> profile = (*passes)->profile();
  Result<LiveMesh> profiled = (*passes)->read_back();
  if (!profiled) return fail(profiled.error().message);
  if (profiled->mesh.indices != mesh->mesh.indices) return fail("profiled mesh differs");

  std::printf("renderer: %s\n", (*context)->renderer().c_str());
  std::printf("%s, %zu map(s) of %dx%d, E = %g: %zu triangles, fix-up rounds %d, seam rounds %d\n",
              argv[1], on_gpu.size(), on_gpu[0].width, on_gpu[0].height, max_error,
              mesh->mesh.num_triangles(), mesh->fixup_rounds, mesh->seam_rounds);
  std::uint64_t hash = 1469598103934665603ull;  // FNV-1a of the indices and positions' bits
  const auto mix = [&](const void* data, std::size_t bytes) {
    for (std::size_t i = 0; i < bytes; ++i)
      hash = (hash ^ static_cast<const unsigned char*>(data)[i]) * 1099511628211ull;
  };
  mix(mesh->mesh.indices.data(), mesh->mesh.indices.size() * sizeof(std::uint32_t));
  mix(mesh->mesh.positions.data(), mesh->mesh.positions.size() * sizeof(float));
  std::printf("mesh hash %016llx\n", static_cast<unsigned long long>(hash));
  std::printf("generation unprofiled, median of %d: wall %.1f ms, process CPU %.1f ms\n\n", frames,
              1e3 * median(wall), 1e3 * median(cpu));
  double total = 0;
  double total_wall = 0, total_cpu = 0;
  for (const auto& p : profile)
    total += p.seconds, total_wall += p.wall_seconds, total_cpu += p.cpu_seconds;
  std::printf("%-13s %-16s %10s %9s %9s %9s %7s\n", "phase", "pass", "dispatches", "GPU ms",
              "wall ms", "CPU ms", "share");
  std::string last;
  double phase_total = 0, phase_wall = 0, phase_cpu = 0;
  const auto phase_line = [&] {
    if (!last.empty())
      std::printf("%-13s %-16s %10s %9.1f %9.1f %9.1f %6.1f%%\n", last.c_str(), "(all)", "",
                  1e3 * phase_total / frames, 1e3 * phase_wall / frames, 1e3 * phase_cpu / frames,
                  100 * phase_cpu / total_cpu);
  };
  for (const auto& p : profile) {
    if (p.phase != last) {
      phase_line();
      last = p.phase, phase_total = 0, phase_wall = 0, phase_cpu = 0;
    }
    phase_total += p.seconds, phase_wall += p.wall_seconds, phase_cpu += p.cpu_seconds;
    std::printf("%-13s %-16s %10.1f %9.1f %9.1f %9.1f %6.1f%%\n", p.phase.c_str(), p.pass.c_str(),
                static_cast<double>(p.dispatches) / frames, 1e3 * p.seconds / frames,
                1e3 * p.wall_seconds / frames, 1e3 * p.cpu_seconds / frames,
                100 * p.cpu_seconds / total_cpu);
  }
  phase_line();
  std::printf("%-13s %-16s %10s %9.1f %9.1f %9.1f\n", "total", "", "", 1e3 * total / frames,
              1e3 * total_wall / frames, 1e3 * total_cpu / frames);
  std::printf(
      "(per frame. GPU ms: GL_TIME_ELAPSED; wall ms: the clock between glFinish calls "
      "around each command; CPU ms: the process's CPU time (all threads) over the same "
      "span; share: of the CPU total)\n");
  return 0;
}
