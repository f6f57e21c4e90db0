#include <sys/mman.h>

#include <algorithm>

#include <tbb/parallel_for.h>

#include <lightvol/core/buffer.h>

namespace lightvol {

void populate_in_parallel(std::initializer_list<std::pair<const void*, std::size_t>> ranges) {
#ifdef MADV_POPULATE_WRITE
  constexpr std::uintptr_t kPage = 4096, kBlock = std::uintptr_t{32} << 20;
  std::vector<std::pair<std::uintptr_t, std::uintptr_t>> blocks;
  for (const auto& [start, bytes] : ranges) {
    const auto begin = reinterpret_cast<std::uintptr_t>(start);
    const std::uintptr_t first = (begin + kPage - 1) & ~(kPage - 1);
    const std::uintptr_t end = (begin + bytes) & ~(kPage - 1);
    for (std::uintptr_t at = first; at < end; at += kBlock)
      blocks.emplace_back(at, std::min(kBlock, end - at));
  }
  tbb::parallel_for(std::size_t{0}, blocks.size(), [&](std::size_t i) {
    ::madvise(reinterpret_cast<void*>(blocks[i].first), blocks[i].second, MADV_POPULATE_WRITE);
  });
#else
  (void)ranges;
#endif
}

void populate(std::initializer_list<std::pair<const void*, std::size_t>> ranges) {
#ifdef MADV_POPULATE_WRITE
  constexpr std::uintptr_t kPage = 4096;
  for (const auto& [start, bytes] : ranges) {
    const auto begin = reinterpret_cast<std::uintptr_t>(start);
    const std::uintptr_t first = (begin + kPage - 1) & ~(kPage - 1);
    const std::uintptr_t end = (begin + bytes) & ~(kPage - 1);
    if (end > first) ::madvise(reinterpret_cast<void*>(first), end - first, MADV_POPULATE_WRITE);
  }
#else
  (void)ranges;
#endif
}

}  // namespace lightvol
