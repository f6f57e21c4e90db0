#include <sys/mman.h>

#include <algorithm>
#include <limits>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <lightvol/core/buffer.h>

namespace lightvol {

#ifdef MADV_POPULATE_WRITE
namespace {

constexpr std::uintptr_t kPage = 4096;

// The whole pages of each range, as (first page, end) address pairs split into blocks of at most
// `block` bytes.
std::vector<std::pair<std::uintptr_t, std::uintptr_t>> page_blocks(
    std::initializer_list<std::pair<const void*, std::size_t>> ranges, std::uintptr_t block) {
  std::vector<std::pair<std::uintptr_t, std::uintptr_t>> blocks;
  for (const auto& [start, bytes] : ranges) {
    const auto begin = reinterpret_cast<std::uintptr_t>(start);
    const std::uintptr_t first = (begin + kPage - 1) & ~(kPage - 1);
    const std::uintptr_t end = (begin + bytes) & ~(kPage - 1);
    for (std::uintptr_t at = first; at < end;) {
      const std::uintptr_t n = std::min(block, end - at);
      blocks.emplace_back(at, n);
      at += n;
    }
  }
  return blocks;
}

void populate_block(const std::pair<std::uintptr_t, std::uintptr_t>& b) {
  ::madvise(reinterpret_cast<void*>(b.first), b.second, MADV_POPULATE_WRITE);
}

}  // namespace
#endif

void populate_in_parallel(std::initializer_list<std::pair<const void*, std::size_t>> ranges) {
#ifdef MADV_POPULATE_WRITE
  std::uintptr_t bytes = 0;
  for (const auto& range : ranges) bytes += range.second;
  const auto threads =
      static_cast<std::uintptr_t>(std::max(1, tbb::this_task_arena::max_concurrency()));
  const std::uintptr_t block =
      std::clamp(bytes / (8 * threads), std::uintptr_t{2} << 20, std::uintptr_t{32} << 20) &
      ~((std::uintptr_t{2} << 20) - 1);
  const auto blocks = page_blocks(ranges, block);
  tbb::parallel_for(std::size_t{0}, blocks.size(),
                    [&](std::size_t i) { populate_block(blocks[i]); });
#else
  (void)ranges;
#endif
}

void populate(std::initializer_list<std::pair<const void*, std::size_t>> ranges) {
#ifdef MADV_POPULATE_WRITE
  for (const auto& b : page_blocks(ranges, std::numeric_limits<std::uintptr_t>::max()))
    populate_block(b);
#else
  (void)ranges;
#endif
}

}  // namespace lightvol
