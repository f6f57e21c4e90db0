// The static volume build alone (no file I/O), for the synthetic map at several sizes.
#include <benchmark/benchmark.h>

#include <lightvol/volume/static_volume.h>

#include "synthetic_scene.h"

namespace {

lightvol::Light spot() {
  lightvol::Result<lightvol::Light> l = lightvol::parse_light(
      R"({"type": "spot", "position": [0, 10, 0], "direction": [0, -1, 0], "up": [0, 0, -1],
          "fov_y_deg": 60, "near": 1, "far": 20})",
      "bench");
  return *l;
}

void BM_StaticSpotVolume(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const lightvol::DepthImage depth = lightvol::bench::synthetic_scene(n, n);
  const lightvol::Light light = spot();
  for (auto _ : state) {
    lightvol::Result<lightvol::Mesh> mesh =
        lightvol::build_static_volume(light, depth, {}, "bench");
    benchmark::DoNotOptimize(mesh->indices.data());
  }
  state.counters["triangles"] = static_cast<double>(2.0 * n * n - 2);
}
BENCHMARK(BM_StaticSpotVolume)
    ->Arg(1024)
    ->Arg(2048)
    ->Arg(4096)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
