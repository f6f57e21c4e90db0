// Static omni volume builds in memory (six W×W faces → 12W² − 4 triangles) from the synthetic
// room (omni_scene.h), at 6×512² and 6×1024². Peak memory is the process's after the benchmark:
// run one size at a time (--benchmark_filter) to attribute it.
#include <benchmark/benchmark.h>

#include <lightvol/core/stages.h>
#include <lightvol/volume/omni_volume.h>

#include "omni_scene.h"

namespace {

void BM_StaticOmniBuild(benchmark::State& state) {
  const int w = static_cast<int>(state.range(0));
  const lightvol::Light light = *lightvol::parse_light(lightvol::bench::omni_scene_light_json(), "bench");
  const lightvol::CubeFaces cube = lightvol::bench::omni_scene(w);
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

}  // namespace

BENCHMARK_MAIN();
