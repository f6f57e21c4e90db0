#include <algorithm>
#include <bit>
#include <cstring>
#include <optional>

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

namespace {

// Whether two vertices have bit-identical positions, by a hash table of the vertices in order;
// nullopt when its probes exceed a linear budget (positions chosen to collide), which leaves the
// answer to the sort below. A slot holds the vertex and 32 more bits of its position's hash, so
// that a probe rarely reads another vertex's position (a cache miss).
std::optional<bool> any_identical_positions(const Mesh& mesh) {
  const std::size_t nv = mesh.num_vertices();
  if (nv < 2) return false;
  if (nv >= 0xffffffffu) return std::nullopt;
  const std::size_t mask = std::bit_ceil(2 * nv) - 1;
  constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  std::vector<std::uint64_t> table(mask + 1, kEmpty);
  const float* p = mesh.positions.data();
  const auto hash_of = [&](std::size_t v) {
    std::uint32_t bits[3];
    std::memcpy(bits, p + 3 * v, 12);
    std::uint64_t h = bits[0] * 0x9e3779b97f4a7c15ull ^ bits[1] * 0xc2b2ae3d27d4eb4full ^
                      bits[2] * 0x165667b19e3779f9ull;
    h ^= h >> 31;
    h *= 0xbf58476d1ce4e5b9ull;
    h ^= h >> 29;
    return h;
  };
  constexpr std::size_t kAhead = 16;  // prefetch the slot of the vertex this far ahead
  std::size_t probes = 0;
  const std::size_t budget = 8 * nv;
  for (std::size_t v = 0; v < nv; ++v) {
    if (v + kAhead < nv) __builtin_prefetch(&table[hash_of(v + kAhead) & mask]);
    const std::uint64_t h = hash_of(v);
    const std::uint64_t tag = h & 0xffffffff00000000ull;
    for (std::size_t s = static_cast<std::size_t>(h) & mask;; s = (s + 1) & mask) {
      const std::uint64_t entry = table[s];
      if (entry == kEmpty) {
        table[s] = tag | v;
        break;
      }
      if ((entry & 0xffffffff00000000ull) == tag &&
          std::memcmp(p + 3 * (entry & 0xffffffffu), p + 3 * v, 12) == 0)
        return true;
      if (++probes > budget) return std::nullopt;
    }
  }
  return false;
}

}  // namespace

Mesh weld_identical_positions(Mesh mesh) {
  // Most meshes have no two vertices at one position: a hash table says so in linear time, and
  // the mesh is returned as it is.
  if (any_identical_positions(mesh) == std::optional<bool>(false)) return mesh;
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
