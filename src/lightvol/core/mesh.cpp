#include <algorithm>
#include <cstring>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

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

// The sum is the one tbb::parallel_deterministic_reduce forms over blocked_range(0, n, 2^16):
// ranges above the grain split at their midpoint, each leaf sums its triangles in order from 0,
// and each split adds its left half's sum to its right half's.
namespace {
constexpr std::size_t kVolumeGrain = std::size_t{1} << 16;
}  // namespace

SignedVolumeSum::SignedVolumeSum(std::size_t triangles) : triangles_(triangles) {
  split(0, triangles);
  leaf_begin_.push_back(triangles);
  leaf_sum_.assign(leaf_begin_.size() - 1, 0.0);
}

void SignedVolumeSum::split(std::size_t begin, std::size_t end) {
  if (end - begin > kVolumeGrain) {
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
  if (end - begin > kVolumeGrain) {
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

Status MeshBufferStream::positions(const PositionSink& sink) {
  constexpr std::size_t kBlock = std::size_t{1} << 16;
  const std::size_t n = mesh_.num_vertices();
  for (std::size_t v = 0; v < n; v += kBlock)
    if (!sink(&mesh_.positions[3 * v], std::min(kBlock, n - v))) return {};
  return {};
}

Status MeshBufferStream::triangles(const TriangleSink& sink) {
  constexpr std::size_t kBlock = std::size_t{1} << 16;
  const std::size_t n = mesh_.num_triangles();
  for (std::size_t t = 0; t < n; t += kBlock)
    if (!sink(&mesh_.indices[3 * t], std::min(kBlock, n - t))) return {};
  return {};
}

Mesh weld_identical_positions(const Mesh& mesh) {
  // By sorting (bits of x, y, z, then the vertex): O(n log n) whatever the positions, where a hash
  // table can be made quadratic by positions chosen to collide. Each run of equal positions is
  // one vertex, numbered in the order of its first occurrence, so the result is the one a
  // first-come map would give.
  struct Record {
    std::uint32_t x, y, z, v;
    bool operator<(const Record& o) const {
      return x != o.x ? x < o.x : y != o.y ? y < o.y : z != o.z ? z < o.z : v < o.v;
    }
    bool same_position(const Record& o) const { return x == o.x && y == o.y && z == o.z; }
  };
  const std::size_t nv = mesh.num_vertices();
  std::vector<Record> records(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    std::memcpy(&records[v], &mesh.positions[3 * v], 12);
    records[v].v = static_cast<std::uint32_t>(v);
  }
  tbb::parallel_sort(records.begin(), records.end());
  // first[v]: the first vertex at v's position.
  std::vector<std::uint32_t> first(nv);
  for (std::size_t i = 0, run = 0; i < nv; ++i) {
    if (i == 0 || !records[i].same_position(records[i - 1])) run = i;
    first[records[i].v] = records[run].v;
  }
  records = {};
  Mesh out;
  std::vector<std::uint32_t>& remap = first;  // becomes the new index of each vertex, in place
  std::size_t kept = 0;
  for (std::size_t v = 0; v < nv; ++v) kept += first[v] == v;
  out.positions.resize(3 * kept);
  for (std::size_t v = 0, next = 0; v < nv; ++v) {
    if (first[v] == v) {  // a first occurrence: numbered now (first[u] ≤ u, so u's first is set)
      std::memcpy(&out.positions[3 * next], &mesh.positions[3 * v], 12);
      remap[v] = static_cast<std::uint32_t>(next++);
    } else {
      remap[v] = remap[first[v]];
    }
  }
  out.indices.resize(mesh.indices.size());
  for (std::size_t i = 0; i < mesh.indices.size(); ++i) out.indices[i] = remap[mesh.indices[i]];
  return out;
}

}  // namespace lightvol
