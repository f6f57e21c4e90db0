// What running Draco's decoder in a child process costs (src/lightvol/core/detail/isolated.h):
// decoding the Draco encoding of static spot volumes, isolated as lightvol reads them, and in this
// process.
//   tests/bench/draco_bench [--benchmark_filter=...]
#include <map>
#include <string>

#include <benchmark/benchmark.h>

#include <lightvol/export/export.h>
#include <lightvol/io/detail/draco_mesh.h>
#include <lightvol/volume/static_volume.h>

#include "synthetic_scene.h"

namespace {

// The 16-bit Draco encoding of the W×W synthetic spot volume, made once per size.
const std::string& encoded(int width) {
  static std::map<int, std::string> cache;
  std::string& bytes = cache[width];
  if (bytes.empty()) {
    const lightvol::Light light = *lightvol::parse_light(
        R"({"type": "spot", "position": [0, 10, 0], "direction": [0, -1, 0], "up": [0, 0, -1],
            "fov_y_deg": 60, "near": 1, "far": 20})",
        "bench");
    const lightvol::Mesh mesh = *lightvol::build_static_volume(
        light, lightvol::bench::synthetic_scene(width, width), {}, "bench");
    bytes = *lightvol::encode_draco(mesh, 16);
  }
  return bytes;
}

template <bool kIsolated>
void BM_DecodeDraco(benchmark::State& state) {
  const std::string& bytes = encoded(static_cast<int>(state.range(0)));
  std::size_t triangles = 0;
  for (auto _ : state) {
    const lightvol::Result<lightvol::detail::DracoMesh> mesh =
        kIsolated ? lightvol::detail::decode_draco(bytes)
                  : lightvol::detail::decode_draco_unisolated(bytes);
    if (!mesh) {
      state.SkipWithError(mesh.error().message.c_str());
      return;
    }
    triangles = mesh->mesh.num_triangles();
    benchmark::DoNotOptimize(triangles);
  }
  state.counters["triangles"] = static_cast<double>(triangles);
  state.counters["file_MiB"] = static_cast<double>(bytes.size()) / (1 << 20);
}
BENCHMARK(BM_DecodeDraco<true>)
    ->Name("isolated")
    ->Arg(64)
    ->Arg(1024)
    ->Arg(2048)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Repetitions(5)
    ->ReportAggregatesOnly();
BENCHMARK(BM_DecodeDraco<false>)
    ->Name("in_process")
    ->Arg(64)
    ->Arg(1024)
    ->Arg(2048)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Repetitions(5)
    ->ReportAggregatesOnly();

}  // namespace

BENCHMARK_MAIN();
