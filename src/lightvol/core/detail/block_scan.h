// A parallel scan of many items for the first block where a test fails: the checks over every
// texel of a large map (depth/depth_image.cpp, tessellate/texel_depths.cpp). Include it only from
// files compiled with -fopenmp-simd (src/CMakeLists.txt): its loop vectorizes there.
#pragma once

#include <algorithm>
#include <cstddef>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

namespace lightvol::detail {

constexpr std::size_t kScanBlock = std::size_t{1} << 16;

// The first item of the first block of kScanBlock items of [0, n) holding an item k for which
// holds(k) is false, or n when there is none (then every item holds). Blocks in parallel, each
// tested whole with no early exit (the loop vectorizes); a block after a failing one the same task
// found is skipped.
template <class Holds>
std::size_t first_failing_block(std::size_t n, const Holds& holds) {
  const std::size_t blocks = (n + kScanBlock - 1) / kScanBlock;
  const std::size_t failing = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, blocks), blocks,
      [&](const tbb::blocked_range<std::size_t>& range, std::size_t first) {
        for (std::size_t b = range.begin(); b != range.end() && b < first; ++b) {
          const std::size_t end = std::min(n, (b + 1) * kScanBlock);
          unsigned all = 1;
#pragma omp simd reduction(& : all)
          for (std::size_t k = b * kScanBlock; k < end; ++k) all &= holds(k) ? 1u : 0u;
          if (!all) return b;
        }
        return first;
      },
      [](std::size_t a, std::size_t b) { return std::min(a, b); });
  return std::min(n, failing * kScanBlock);
}

}  // namespace lightvol::detail
