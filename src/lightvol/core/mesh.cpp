#include <algorithm>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <lightvol/core/mesh.h>
#include <lightvol/core/mesh_stream.h>

namespace lightvol {

Bounds bounding_box(const Mesh& mesh) {
  Bounds b;
  const std::size_t n = mesh.num_vertices();
  if (n == 0) return b;
  for (int k = 0; k < 3; ++k) b.min[k] = b.max[k] = mesh.positions[k];
  for (std::size_t v = 0; v < n; ++v) {
    for (int k = 0; k < 3; ++k) {
      const double x = mesh.positions[3 * v + k];
      b.min[k] = std::min(b.min[k], x);
      b.max[k] = std::max(b.max[k], x);
    }
  }
  return b;
}

double signed_volume(const Mesh& mesh) {
  SignedVolumeSum sum(mesh.num_triangles());
  const float* p = mesh.positions.data();
  const std::uint32_t* idx = mesh.indices.data();
  sum.add(0, mesh.num_triangles(),
          [&](std::size_t t, int k) { return p + 3 * std::size_t{idx[3 * t + k]}; });
  return sum.volume();
}

// The sum is the one tbb::parallel_deterministic_reduce forms over blocked_range(0, n,
// kSignedVolumeGrain): ranges above the grain split at their midpoint, each leaf sums its
// triangles in order from 0, and each split adds its left half's sum to its right half's.

SignedVolumeSum::SignedVolumeSum(std::size_t triangles) : triangles_(triangles) {
  split(0, triangles);
  leaf_begin_.push_back(triangles);
  leaf_sum_.assign(leaf_begin_.size() - 1, 0.0);
}

void SignedVolumeSum::split(std::size_t begin, std::size_t end) {
  if (end - begin > kSignedVolumeGrain) {
    const std::size_t middle = begin + (end - begin) / 2u;
    split(begin, middle);
    split(middle, end);
    return;
  }
  leaf_begin_.push_back(begin);
}

void SignedVolumeSum::for_each_leaf(
    std::size_t begin, std::size_t end,
    const std::function<void(std::size_t, std::size_t, std::size_t)>& f) {
  if (begin >= end) return;
  const auto leaf_of = [&](std::size_t t) {
    return static_cast<std::size_t>(std::upper_bound(leaf_begin_.begin(), leaf_begin_.end(), t) -
                                    leaf_begin_.begin() - 1);
  };
  const std::size_t first = leaf_of(begin), last = leaf_of(end - 1);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(first, last + 1, 1),
                    [&](const tbb::blocked_range<std::size_t>& leaves) {
                      for (std::size_t l = leaves.begin(); l != leaves.end(); ++l)
                        f(l, std::max(begin, leaf_begin_[l]), std::min(end, leaf_begin_[l + 1]));
                    });
}

double SignedVolumeSum::fold(std::size_t begin, std::size_t end, std::size_t* leaf) const {
  if (end - begin > kSignedVolumeGrain) {
    const std::size_t middle = begin + (end - begin) / 2u;
    const double left = fold(begin, middle, leaf);
    return left + fold(middle, end, leaf);
  }
  return leaf_sum_[(*leaf)++];
}

double SignedVolumeSum::volume() const {
  std::size_t leaf = 0;
  return fold(0, triangles_, &leaf) / 6.0;
}

namespace {

// Hands `count` records of three values each from `buffer` to `sink`, 2^16 records at a time,
// until the sink says stop.
template <class T, class Sink>
Status in_blocks(const std::vector<T>& buffer, std::size_t count, const Sink& sink) {
  constexpr std::size_t kBlock = std::size_t{1} << 16;
  for (std::size_t i = 0; i < count; i += kBlock)
    if (!sink(&buffer[3 * i], std::min(kBlock, count - i))) break;
  return {};
}

}  // namespace

Status MeshBufferStream::positions(const PositionSink& sink) {
  return in_blocks(mesh_.positions, mesh_.num_vertices(), sink);
}

Status MeshBufferStream::triangles(const TriangleSink& sink) {
  return in_blocks(mesh_.indices, mesh_.num_triangles(), sink);
}

}  // namespace lightvol
