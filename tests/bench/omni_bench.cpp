// Omni volume builds in memory from the synthetic room (omni_scene.h), at 6×512² and 6×1024²:
// static (six W×W faces → 12W² − 4 triangles) and adaptive at max errors 0.01 and 0.001 world
// units (the room is 10 × 4 × 8). Peak memory is the process's after the benchmark: run one
// benchmark at a time (--benchmark_filter) to attribute it.
#include <benchmark/benchmark.h>

#include <lightvol/core/stages.h>
#include <lightvol/volume/omni_adaptive.h>
#include <lightvol/volume/omni_volume.h>

#include "support/omni_scene.h"

namespace {

void BM_StaticOmniBuild(benchmark::State& state) {
  const int w = static_cast<int>(state.range(0));
  const lightvol::Light light =
      *lightvol::parse_light(lightvol::test::omni_scene_light_json(), "bench");
  const lightvol::CubeFaces cube = lightvol::test::omni_scene(w);
  std::size_t triangles = 0;
  for (auto _ : state) {
    lightvol::Result<lightvol::Mesh> mesh = lightvol::build_omni_volume(light, cube, {});
    if (!mesh) {
      state.SkipWithError(mesh.error().message.c_str());
      return;
    }
    triangles = mesh->num_triangles();
    benchmark::DoNotOptimize(mesh->indices.data());
  }
  state.counters["triangles"] = static_cast<double>(triangles);
  state.counters["Mtri_per_s"] = benchmark::Counter(static_cast<double>(triangles) / 1e6,
                                                    benchmark::Counter::kIsIterationInvariantRate);
  state.counters["peak_MiB"] = static_cast<double>(lightvol::peak_memory_bytes()) / (1 << 20);
}
BENCHMARK(BM_StaticOmniBuild)->Arg(512)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();

// Arguments: W, and the max error in thousandths of a world unit.
void BM_AdaptiveOmniBuild(benchmark::State& state) {
  const int w = static_cast<int>(state.range(0));
  const lightvol::Light light =
      *lightvol::parse_light(lightvol::test::omni_scene_light_json(), "bench");
  const lightvol::CubeFaces cube = lightvol::test::omni_scene(w);
  lightvol::AdaptiveOptions options;
  options.max_error = static_cast<double>(state.range(1)) / 1000;
  lightvol::AdaptiveReport report;
  lightvol::OmniAdaptiveDetail detail;
  for (auto _ : state) {
    lightvol::Result<lightvol::Mesh> mesh =
        lightvol::build_adaptive_omni_volume(light, cube, {}, options, &report, &detail);
    if (!mesh) {
      state.SkipWithError(mesh.error().message.c_str());
      return;
    }
    benchmark::DoNotOptimize(mesh->indices.data());
  }
  state.counters["triangles"] = static_cast<double>(report.triangles);
  state.counters["seam_tris"] = static_cast<double>(detail.seam_triangles);
  state.counters["seam_rounds"] = detail.seam_rounds;
  state.counters["collapse_rounds"] = detail.collapse_rounds;
  state.counters["pyramid_ms"] = report.pyramid_seconds * 1e3;
  state.counters["peak_MiB"] = static_cast<double>(lightvol::peak_memory_bytes()) / (1 << 20);
}
BENCHMARK(BM_AdaptiveOmniBuild)
    ->Args({512, 10})
    ->Args({512, 1})
    ->Args({1024, 10})
    ->Args({1024, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
