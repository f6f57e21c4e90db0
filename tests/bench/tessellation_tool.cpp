// tessellation_tool N E [FLIP_SWEEPS]: the tessellations of the synthetic N×N map
// (synthetic_scene.h) under the benchmark's directional light (near 0, far 1, linear depth) at max
// error E, in memory: triangles, reached error (RefinementPyramid::measure), time of each stage,
// smallest angle and area.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <lightvol/light/light.h>
#include <lightvol/tessellate/adaptive_grid.h>
#include <lightvol/tessellate/collapse_grid.h>

#include "cpu_seconds.h"
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

double since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace

using lightvol::bench::cpu_seconds;

int main(int argc, char** argv) {
  if (argc != 3 && argc != 4) {
    std::fprintf(stderr, "usage: tessellation_tool N E [FLIP_SWEEPS]\n");
    return 2;
  }
  const int n = std::atoi(argv[1]);
  const double e = std::atof(argv[2]);
  const lightvol::DepthImage depth = lightvol::bench::synthetic_scene(n, n);
  const lightvol::Light light = bench_light(n);
  double c0 = cpu_seconds();
  auto t0 = std::chrono::steady_clock::now();
  auto texels = lightvol::TexelDepths::create(light, depth, 0, "bench");
  const lightvol::RefinementPyramid pyramid(std::move(*texels), lightvol::Refinement::max_error);
  const double tp = since(t0), cp = cpu_seconds() - c0;
  c0 = cpu_seconds();
  t0 = std::chrono::steady_clock::now();
  const lightvol::AdaptiveGrid quad = pyramid.tessellate(e, true);
  const double tq = since(t0), cq = cpu_seconds() - c0;
  const lightvol::GridQuality qq = lightvol::grid_quality(quad);
  std::printf(
      "quadtree  triangles %zu  reached %.8f  pyramid %.3f s (CPU %.3f s)  tessellate %.3f s (CPU "
      "%.3f s)  angle %.3f area %.1f\n",
      quad.num_triangles(), pyramid.measure(quad), tp, cp, tq, cq, qq.min_angle_degrees,
      qq.min_area);
  lightvol::CollapseReport r;
  lightvol::CollapseOptions o;
  if (argc == 4) o.flip_sweeps = std::atoi(argv[3]);
  c0 = cpu_seconds();
  const lightvol::AdaptiveGrid col = lightvol::collapse_grid(pyramid.texels(), quad, e, o, &r);
  const double cc = cpu_seconds() - c0;
  const lightvol::GridQuality qc = lightvol::grid_quality(col);
  std::printf(
      "collapse  triangles %zu  reached %.8f  collapse %.3f s (CPU %.3f s; %d rounds, %llu "
      "attempts, %llu collapses, %llu flips)  angle %.3f area %.1f\n",
      col.num_triangles(), pyramid.measure(col), r.seconds, cc, r.rounds,
      static_cast<unsigned long long>(r.attempts), static_cast<unsigned long long>(r.collapses),
      static_cast<unsigned long long>(r.flips), qc.min_angle_degrees, qc.min_area);
  // Triangles with a smallest angle under 1° and 5° (texel space).
  std::size_t under1 = 0, under5 = 0;
  const auto w = static_cast<std::uint32_t>(col.width);
  for (std::size_t k = 0; k < col.num_triangles(); ++k) {
    double x[3], y[3];
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t id = col.vertices[col.indices[3 * k + c]];
      x[c] = id % w, y[c] = id / w;
    }
    const double area2 = std::abs((x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]));
    double smallest = 180;
    for (int c = 0; c < 3; ++c) {
      const int a = (c + 1) % 3, b = (c + 2) % 3;
      const double dot = (x[a] - x[c]) * (x[b] - x[c]) + (y[a] - y[c]) * (y[b] - y[c]);
      smallest = std::min(smallest, std::atan2(area2, dot) * 180 / M_PI);
    }
    under1 += smallest < 1;
    under5 += smallest < 5;
  }
  std::printf("collapse  triangles under 1°: %zu, under 5°: %zu\n", under1, under5);
  return 0;
}
