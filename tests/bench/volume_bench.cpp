// The static volume build (no file I/O; the float32 guard included), for the synthetic map at
// several sizes; the float32 guard (check_representable) alone on the held volume; the streamed
// volume (StaticVolumeStream, which runs the guard as it goes) handed to sinks that keep nothing.
#include <benchmark/benchmark.h>

#include <lightvol/volume/float32_guard.h>
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

void BM_CheckRepresentable(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const lightvol::DepthImage depth = lightvol::bench::synthetic_scene(n, n);
  const lightvol::Light light = spot();
  const lightvol::Result<lightvol::Mesh> mesh =
      lightvol::build_static_volume(light, depth, {}, "bench");
  for (auto _ : state) {
    const lightvol::Status s =
        lightvol::check_representable(*mesh, light, lightvol::Space::world, "bench");
    benchmark::DoNotOptimize(s.ok());
  }
}
BENCHMARK(BM_CheckRepresentable)
    ->Arg(1024)
    ->Arg(4096)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_StaticVolumeStream(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const lightvol::DepthImage depth = lightvol::bench::synthetic_scene(n, n);
  const lightvol::Light light = spot();
  for (auto _ : state) {
    lightvol::StaticVolumeStream stream(light, depth, {}, "bench", "bench");
    float sum = 0;
    const lightvol::Status p = stream.positions([&](const float* xyz, std::size_t count) {
      sum += xyz[3 * count - 1];
      return true;
    });
    std::uint64_t last = 0;
    const lightvol::Status t = stream.triangles([&](const std::uint32_t* abc, std::size_t count) {
      last += abc[3 * count - 1];
      return true;
    });
    benchmark::DoNotOptimize(sum);
    benchmark::DoNotOptimize(last);
    benchmark::DoNotOptimize(p.ok() && t.ok());
  }
}
BENCHMARK(BM_StaticVolumeStream)
    ->Arg(1024)
    ->Arg(4096)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
