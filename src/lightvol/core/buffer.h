// Allocation of the large flat buffers a volume lives in.
#pragma once

#include <sys/mman.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace lightvol {

// Reserves room for `capacity` elements (so later appends never copy the buffer) and asks the
// kernel to back large buffers with transparent huge pages: a 33-million-triangle volume then
// takes hundreds, not hundreds of thousands, of page faults to fill. Advice only: harmless where
// huge pages are unavailable.
template <class T>
void reserve_large(std::vector<T>& buffer, std::size_t capacity) {
  buffer.reserve(capacity);
  constexpr std::size_t kHuge = std::size_t{2} << 20;
  const std::size_t bytes = capacity * sizeof(T);
  if (bytes < 4 * kHuge) return;
  const auto begin = reinterpret_cast<std::uintptr_t>(buffer.data());
  const std::uintptr_t aligned = (begin + kHuge - 1) & ~(kHuge - 1);
  const std::uintptr_t end = (begin + bytes) & ~(kHuge - 1);
  if (end > aligned) ::madvise(reinterpret_cast<void*>(aligned), end - aligned, MADV_HUGEPAGE);
}

}  // namespace lightvol
