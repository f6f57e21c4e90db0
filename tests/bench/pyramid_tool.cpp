// pyramid_tool MAP LIGHT CAP REPS THREADS: the adaptive build's error pyramid alone, REPS times on
// MAP (a depth image) under LIGHT (a light JSON file), capped at CAP (the build's --max-error) and
// with at most THREADS threads. Per build one line: the process's CPU seconds (user + sys) and the
// wall seconds of the pyramid (RefinementPyramid's constructor; the texel depths are made before),
// the cells measured and a hash (FNV-1a) of every level's values, which changes with any value.
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>

#include <tbb/global_control.h>

#include <lightvol/depth/depth_image.h>
#include <lightvol/light/light.h>
#include <lightvol/tessellate/adaptive_grid.h>
#include <lightvol/tessellate/detail/lattice.h>

#include "cpu_seconds.h"

using lightvol::bench::cpu_seconds;

int main(int argc, char** argv) {
  if (argc != 6) {
    std::fprintf(stderr, "usage: pyramid_tool MAP LIGHT CAP REPS THREADS\n");
    return 2;
  }
  std::stringstream json;
  json << std::ifstream(argv[2]).rdbuf();
  const lightvol::Result<lightvol::Light> light = lightvol::parse_light(json.str(), argv[2]);
  const lightvol::Result<lightvol::DepthImage> depth = lightvol::read_depth_image(argv[1], {});
  if (!light || !depth) {
    std::fprintf(stderr, "pyramid_tool: %s\n",
                 (!light ? light.error() : depth.error()).message.c_str());
    return 2;
  }
  const double cap = std::atof(argv[3]);
  const int reps = std::atoi(argv[4]);
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                              static_cast<std::size_t>(std::atoi(argv[5])));
  for (int r = 0; r < reps; ++r) {
    lightvol::Result<lightvol::TexelDepths> texels =
        lightvol::TexelDepths::create(*light, *depth, 0, argv[1], true);
    if (!texels) {
      std::fprintf(stderr, "pyramid_tool: %s\n", texels.error().message.c_str());
      return 2;
    }
    const double cpu = cpu_seconds();
    const auto start = std::chrono::steady_clock::now();
    const lightvol::RefinementPyramid pyramid(std::move(*texels), lightvol::Refinement::max_error,
                                              cap);
    const double cpu_used = cpu_seconds() - cpu;
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const lightvol::detail::Quadtree q(pyramid.texels().width(), pyramid.texels().height());
    std::uint64_t hash = 14695981039346656037ull;
    for (int level = 1; level <= q.top; ++level)
      for (std::size_t cell = 0; cell < q.cells(level); ++cell) {
        const float v = pyramid.value(level, cell);
        std::uint32_t bits = 0;
        std::memcpy(&bits, &v, sizeof bits);
        hash = (hash ^ bits) * 1099511628211ull;
      }
    std::printf("cpu %.3f wall %.3f measured %llu hash %016llx\n", cpu_used, wall,
                static_cast<unsigned long long>(pyramid.cells_measured()),
                static_cast<unsigned long long>(hash));
  }
  return 0;
}
