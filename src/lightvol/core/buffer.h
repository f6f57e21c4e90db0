// Allocation of the large flat buffers a volume lives in.
#pragma once

#include <sys/mman.h>

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <memory>
#include <utility>
#include <vector>

namespace lightvol {

// Asks the kernel to back the whole 2 MiB pages inside [data, data + bytes) with transparent huge
// pages, when there are at least four 2 MiB's worth of bytes: a 33-million-triangle volume then
// takes hundreds, not hundreds of thousands, of page faults to fill. Advice only: harmless where
// huge pages are unavailable.
inline void advise_huge_pages(const void* data, std::size_t bytes) {
  constexpr std::size_t kHuge = std::size_t{2} << 20;
  if (bytes < 4 * kHuge) return;
  const auto begin = reinterpret_cast<std::uintptr_t>(data);
  const std::uintptr_t aligned = (begin + kHuge - 1) & ~(kHuge - 1);
  const std::uintptr_t end = (begin + bytes) & ~(kHuge - 1);
  if (end > aligned) ::madvise(reinterpret_cast<void*>(aligned), end - aligned, MADV_HUGEPAGE);
}

// Maps the pages of each (start, bytes) range in blocks of 2 to 32 MiB (about eight a thread), in
// parallel, before they are
// first written (MADV_POPULATE_WRITE, Linux 5.14; advice only: without it the first write maps
// them, in one thread). The kernel zeroes fresh pages as it maps them, and on a virtual machine
// that is the slowest part of filling a large buffer: both threads share it (buffer.cpp).
void populate_in_parallel(std::initializer_list<std::pair<const void*, std::size_t>> ranges);
// The same in this thread alone (one madvise per range), for a thread that maps pages while the
// other cores have other work.
void populate(std::initializer_list<std::pair<const void*, std::size_t>> ranges);

// Whether loops written for vectorized lanes (the check's face pass, the float32 guard's) run
// vectorized here: their AVX2 or AVX-512 versions (GCC's target_clones on x86-64). Elsewhere
// they would run one lane at a time, slower than the code they replace, which then runs instead.
inline bool vector_lanes() {
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
  static const bool avx2 = __builtin_cpu_supports("avx2");
  return avx2;
#else
  return false;
#endif
}

// Reserves room for `capacity` elements (so later appends never copy the buffer), on huge pages
// when large.
template <class T>
void reserve_large(std::vector<T>& buffer, std::size_t capacity) {
  buffer.reserve(capacity);
  advise_huge_pages(buffer.data(), capacity * sizeof(T));
}

// Before a large buffer's elements [from, to) are first written in one thread: their pages mapped
// by all cores (populate_in_parallel), so that the kernel's zeroing of fresh pages, the slowest
// part of filling a large buffer on a virtual machine, is not left to that one thread.
template <class T>
void populate_for_fill(const std::vector<T>& buffer, std::size_t from, std::size_t to) {
  constexpr std::size_t kLarge = std::size_t{16} << 20;
  if (to <= from || (to - from) * sizeof(T) < kLarge) return;
  populate_in_parallel({{buffer.data() + from, (to - from) * sizeof(T)}});
}

// Makes `buffer` hold `n` copies of `value` (its old contents dropped), on huge pages when large:
// the huge-page advice is given before the first write, so filling the buffer takes one page fault
// per 2 MiB instead of one per 4 KiB, and the pages are mapped by all cores (populate_for_fill).
template <class T>
void assign_large(std::vector<T>& buffer, std::size_t n, const T& value) {
  buffer.clear();
  reserve_large(buffer, n);
  populate_for_fill(buffer, 0, n);
  buffer.assign(n, value);
}

// Resizes `buffer` to `n` elements (new ones value-initialized), on huge pages when it has to
// grow into a new allocation that is large, the new elements' pages mapped by all cores.
template <class T>
void resize_large(std::vector<T>& buffer, std::size_t n) {
  reserve_large(buffer, n);
  populate_for_fill(buffer, buffer.size(), n);
  buffer.resize(n);
}

// An array of `n` elements left uninitialized (the caller's parallel loop writes each first, and
// its threads take the page faults), on huge pages when large.
template <class T>
std::unique_ptr<T[]> uninitialized_large(std::size_t n) {
  auto array = std::make_unique_for_overwrite<T[]>(n);
  advise_huge_pages(array.get(), n * sizeof(T));
  return array;
}

}  // namespace lightvol
