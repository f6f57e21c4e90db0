// Allocation of the large flat buffers a volume lives in.
#pragma once

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <memory>
#include <utility>
#include <vector>

namespace lightvol {

// Large buffers are left on the kernel's ordinary pages: no huge-page advice (MADV_HUGEPAGE).
// On a virtual machine whose host takes back the guest's free memory (virtio-balloon's free page
// reporting hands it whole 2 MiB blocks), a fresh huge page is one the host must back again, and
// filling a 650 MB mesh on huge pages took 0.9-1.3 s of the kernel's time against 0.26-0.6 s on
// 4 KiB pages (docs/performance.md, "Large buffers on ordinary pages"); where the system turns
// huge pages on for every mapping, it still does.

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

// Before a large buffer's elements [from, to) are first written in one thread: their pages mapped
// by all cores (populate_in_parallel), so that the kernel's zeroing of fresh pages, the slowest
// part of filling a large buffer on a virtual machine, is not left to that one thread.
template <class T>
void populate_for_fill(const std::vector<T>& buffer, std::size_t from, std::size_t to) {
  constexpr std::size_t kLarge = std::size_t{16} << 20;
  if (to <= from || (to - from) * sizeof(T) < kLarge) return;
  populate_in_parallel({{buffer.data() + from, (to - from) * sizeof(T)}});
}

// Makes `buffer` hold `n` copies of `value` (its old contents dropped), its pages mapped by all
// cores before the fill when large (populate_for_fill).
template <class T>
void assign_large(std::vector<T>& buffer, std::size_t n, const T& value) {
  buffer.clear();
  buffer.reserve(n);
  populate_for_fill(buffer, 0, n);
  buffer.assign(n, value);
}

// Resizes `buffer` to `n` elements (new ones value-initialized), the new elements' pages mapped by
// all cores when they are many.
template <class T>
void resize_large(std::vector<T>& buffer, std::size_t n) {
  buffer.reserve(n);
  populate_for_fill(buffer, buffer.size(), n);
  buffer.resize(n);
}

}  // namespace lightvol
