// The adaptive tessellation's stages in memory, on the synthetic map (synthetic_scene.h) under the
// benchmark's directional light (near 0, far 1, linear depth): texel depths + error pyramid,
// tessellation at 0.001 (balance + emit), measure, assembly. Google Benchmark; CPU and wall time.
#include <benchmark/benchmark.h>

#include <lightvol/light/light.h>
#include <lightvol/volume/adaptive_volume.h>

#include "synthetic_scene.h"

namespace {

lightvol::Light bench_light(int n) {
  const std::string right = std::to_string(n - 1) + ".5";
  const std::string json =
      R"({"type": "directional", "position": [0, 0, 0], "direction": [0, 0, -1],)"
      R"( "up": [0, 1, 0], "ortho": [-0.5, )" +
      right + ", -" + right + R"(, 0.5], "near": 0, "far": 1, "depth": "linear"})";
  return *lightvol::parse_light(json, "bench.json");
}

void BM_Pyramid(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const lightvol::DepthImage depth = lightvol::bench::synthetic_scene(n, n);
  const lightvol::Light light = bench_light(n);
  for (auto _ : state) {
    auto texels = lightvol::TexelDepths::create(light, depth, 0, "bench");
    lightvol::RefinementPyramid pyramid(std::move(*texels), lightvol::Refinement::max_error);
    benchmark::DoNotOptimize(pyramid.seconds());
  }
}

void BM_Tessellate(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const lightvol::DepthImage depth = lightvol::bench::synthetic_scene(n, n);
  const lightvol::Light light = bench_light(n);
  auto texels = lightvol::TexelDepths::create(light, depth, 0, "bench");
  const lightvol::RefinementPyramid pyramid(std::move(*texels), lightvol::Refinement::max_error);
  std::size_t triangles = 0;
  for (auto _ : state) triangles = pyramid.tessellate(0.001, true).num_triangles();
  state.counters["triangles"] = static_cast<double>(triangles);
}

void BM_WholeAdaptiveBuild(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const lightvol::DepthImage depth = lightvol::bench::synthetic_scene(n, n);
  const lightvol::Light light = bench_light(n);
  lightvol::AdaptiveOptions o;
  o.max_error = 0.001;
  std::size_t triangles = 0;
  for (auto _ : state) {
    auto mesh = lightvol::build_adaptive_volume(light, depth, {}, o, "bench");
    triangles = mesh->num_triangles();
  }
  state.counters["triangles"] = static_cast<double>(triangles);
}

BENCHMARK(BM_Pyramid)->Arg(1025)->Arg(4097)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Tessellate)->Arg(1025)->Arg(4097)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_WholeAdaptiveBuild)
    ->Arg(1025)
    ->Arg(4097)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
