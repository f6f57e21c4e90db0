// lightvol check on the 2,093,058-triangle static volume of a 1024² spot map (synthetic, with
// occluders): the linear-time checks with the light, and CGAL's self-intersection test alone.
// Peak memory is the process's (getrusage) after each benchmark; run them one at a time
// (--benchmark_filter) to attribute it.
#include <benchmark/benchmark.h>

#include <lightvol/check/check.h>
#include <lightvol/check/detail/cgal_checks.h>
#include <lightvol/check/detail/exact_checks.h>
#include <lightvol/core/stages.h>
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

const lightvol::Mesh& volume_1024() {
  static const lightvol::Mesh mesh = [] {
    const lightvol::DepthImage depth = lightvol::bench::synthetic_scene(1024, 1024);
    return *lightvol::build_static_volume(spot(), depth, {}, "bench");
  }();
  return mesh;
}

void BM_LinearChecksWithLight(benchmark::State& state) {
  const lightvol::Mesh& mesh = volume_1024();
  const lightvol::Light light = spot();
  bool valid = false;
  for (auto _ : state) {
    const lightvol::CheckReport report = lightvol::check_volume_linear(mesh, &light);
    valid = report.valid();
    benchmark::DoNotOptimize(valid);
  }
  if (!valid) state.SkipWithError("the volume failed its checks");
  state.counters["triangles"] = static_cast<double>(mesh.num_triangles());
  state.counters["peak_MiB"] = static_cast<double>(lightvol::peak_memory_bytes()) / (1 << 20);
}
BENCHMARK(BM_LinearChecksWithLight)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(5);

void BM_CgalSelfIntersection(benchmark::State& state) {
  const lightvol::Mesh& mesh = volume_1024();
  bool intersects = true;
  for (auto _ : state) {
    intersects = lightvol::detail::cgal_does_self_intersect(mesh);
    benchmark::DoNotOptimize(intersects);
  }
  if (intersects) state.SkipWithError("CGAL found a self-intersection");
  state.counters["triangles"] = static_cast<double>(mesh.num_triangles());
  state.counters["peak_MiB"] = static_cast<double>(lightvol::peak_memory_bytes()) / (1 << 20);
}
BENCHMARK(BM_CgalSelfIntersection)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

// lightvol's own self-intersection test (the default engine), stopping at the first pair.
void BM_LightvolSelfIntersection(benchmark::State& state) {
  const lightvol::Mesh& mesh = volume_1024();
  bool intersects = true;
  for (auto _ : state) {
    intersects = lightvol::detail::exact_does_self_intersect(mesh);
    benchmark::DoNotOptimize(intersects);
  }
  if (intersects) state.SkipWithError("a self-intersection was found");
  state.counters["triangles"] = static_cast<double>(mesh.num_triangles());
  state.counters["peak_MiB"] = static_cast<double>(lightvol::peak_memory_bytes()) / (1 << 20);
}
BENCHMARK(BM_LightvolSelfIntersection)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(5);

// CGAL's own parallel test as it comes (PMP::does_self_intersect<Parallel_if_available_tag>, the
// Surface_mesh built first), without cgal_checks' routes for long faces and hubs.
void BM_CgalPmpParallelSelfIntersection(benchmark::State& state) {
  const lightvol::Mesh& mesh = volume_1024();
  bool intersects = true;
  for (auto _ : state) {
    intersects = lightvol::detail::cgal_pmp_does_self_intersect(mesh);
    benchmark::DoNotOptimize(intersects);
  }
  if (intersects) state.SkipWithError("CGAL found a self-intersection");
  state.counters["triangles"] = static_cast<double>(mesh.num_triangles());
}
BENCHMARK(BM_CgalPmpParallelSelfIntersection)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

// Everything without a light: linear checks, CGAL self-intersections (all pairs) and
// bounds-a-volume.
void BM_FullCheckWithoutLight(benchmark::State& state) {
  const lightvol::Mesh& mesh = volume_1024();
  bool valid = false;
  for (auto _ : state) {
    valid = lightvol::check_volume(mesh, nullptr).valid();
    benchmark::DoNotOptimize(valid);
  }
  if (!valid) state.SkipWithError("the volume failed its checks");
  state.counters["peak_MiB"] = static_cast<double>(lightvol::peak_memory_bytes()) / (1 << 20);
}
BENCHMARK(BM_FullCheckWithoutLight)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
