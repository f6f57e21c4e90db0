// weld_identical_positions (declared in mesh.h): vertices with bit-identical positions become one.
//
// The vertices are split by the top bits of their position's hash into partitions of 20 K to 40 K
// vertices, each kept in vertex order; each partition is then looked up in a hash table of its
// own that stays in a core's cache, the partitions in parallel. Identical positions have the same
// hash, so they always meet in one partition, and the first of them (the lowest vertex number)
// is the one in the table when the others arrive: the mapping is that of a first-come map, whatever
// the number of threads. One table over all the vertices (268 MB at 16.8 M vertices) missed the
// cache and the TLB on every vertex.
#include <algorithm>
#include <atomic>
#include <bit>
#include <cstring>
#include <memory>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <lightvol/core/buffer.h>
#include <lightvol/core/mesh.h>

namespace lightvol {
namespace {

std::uint64_t position_hash(const float* p) {
  std::uint32_t bits[3];
  std::memcpy(bits, p, 12);
  std::uint64_t h = bits[0] * 0x9e3779b97f4a7c15ull ^ bits[1] * 0xc2b2ae3d27d4eb4full ^
                    bits[2] * 0x165667b19e3779f9ull;
  h ^= h >> 31;
  h *= 0xbf58476d1ce4e5b9ull;
  h ^= h >> 29;
  return h;
}

constexpr std::size_t kBlock = std::size_t{1} << 16;  // vertices per block of the scatter
constexpr std::uint64_t kEmpty = ~std::uint64_t{0};

// The number of partition bits for `nv` vertices: partitions of 20 K to 40 K vertices (their
// tables, 64 K slots of 8 bytes, about a core's L2 cache), at most 2^12 of them. Smaller ones
// (8 K) were no faster: the scatter into more partitions cost what the tables saved.
int partition_bits(std::size_t nv) {
  int bits = 0;
  while (bits < 12 && (nv >> bits) > 40000) ++bits;
  return bits;
}

// For each vertex, the first vertex (lowest number) at its position, found by the partitioned
// hash tables. Returns false when a partition's probes exceed a linear budget (positions chosen to
// collide), which leaves the answer to the sort in weld_identical_positions. `first` stays empty
// when no two positions are identical.
bool first_at_position(const Mesh& mesh, std::vector<std::uint32_t>* first) {
  const std::size_t nv = mesh.num_vertices();
  const float* p = mesh.positions.data();
  const int bits = partition_bits(nv);
  const std::size_t partitions = std::size_t{1} << bits;
  const auto partition_of = [&](std::uint64_t h) {
    return bits == 0 ? std::size_t{0} : static_cast<std::size_t>(h >> (64 - bits));
  };
  const std::size_t blocks = (nv + kBlock - 1) / kBlock;

  // Each block's count per partition, then its first slot in each partition's run.
  std::vector<std::uint64_t> at(blocks * partitions, 0);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    std::uint64_t* count = &at[b * partitions];
    for (std::size_t v = b * kBlock, end = std::min(nv, v + kBlock); v < end; ++v)
      ++count[partition_of(position_hash(p + 3 * v))];
  });
  std::vector<std::uint64_t> begin(partitions + 1, 0);
  for (std::size_t q = 0, sum = 0; q < partitions; ++q) {
    begin[q] = sum;
    for (std::size_t b = 0; b < blocks; ++b) {
      const std::uint64_t n = at[b * partitions + q];
      at[b * partitions + q] = sum;
      sum += n;
    }
    begin[q + 1] = sum;
  }
  // The entries, by partition and in each in vertex order: the hash's low 32 bits (the slot and
  // a tag that spares most comparisons of positions) and the vertex.
  // Not zeroed: the scatter writes every entry, and its threads take the page faults.
  const std::unique_ptr<std::uint64_t[]> entries =
      std::make_unique_for_overwrite<std::uint64_t[]>(nv);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    std::uint64_t* next = &at[b * partitions];
    for (std::size_t v = b * kBlock, end = std::min(nv, v + kBlock); v < end; ++v) {
      const std::uint64_t h = position_hash(p + 3 * v);
      entries[next[partition_of(h)]++] = (h << 32) | v;
    }
  });
  at = {};

  // Each partition through its table; every entry becomes (the first vertex at its position << 32
  // | the vertex).
  std::atomic<bool> over_budget{false}, any{false};
  tbb::enumerable_thread_specific<std::vector<std::uint64_t>> tables;
  tbb::parallel_for(std::size_t{0}, partitions, [&](std::size_t q) {
    const std::size_t n = begin[q + 1] - begin[q];
    if (n == 0 || over_budget.load(std::memory_order_relaxed)) return;
    std::vector<std::uint64_t>& table = tables.local();
    const std::size_t mask = std::bit_ceil(2 * n) - 1;
    table.assign(mask + 1, kEmpty);
    std::size_t probes = 0;
    bool found = false;
    for (std::uint64_t *e = &entries[begin[q]], *end = e + n; e != end; ++e) {
      const std::uint64_t entry = *e;
      const std::uint64_t tag = entry & 0xffffffff00000000ull;
      const std::uint32_t v = static_cast<std::uint32_t>(entry);
      std::uint64_t first_entry = (std::uint64_t{v} << 32) | v;
      for (std::size_t s = static_cast<std::size_t>(entry >> 32) & mask;; s = (s + 1) & mask) {
        const std::uint64_t slot = table[s];
        if (slot == kEmpty) {
          table[s] = entry;
          break;
        }
        const std::uint32_t u = static_cast<std::uint32_t>(slot);
        if ((slot & 0xffffffff00000000ull) == tag &&
            std::memcmp(p + 3 * std::size_t{u}, p + 3 * std::size_t{v}, 12) == 0) {
          first_entry = (std::uint64_t{u} << 32) | v;
          found = true;
          break;
        }
        if (++probes > 8 * n + 64) {
          over_budget = true;
          return;
        }
      }
      *e = first_entry;
    }
    if (found) any = true;
  });
  if (over_budget) return false;
  if (!any) return true;
  first->resize(nv);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, kBlock),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        const std::uint64_t e = entries[i];
                        (*first)[static_cast<std::uint32_t>(e)] =
                            static_cast<std::uint32_t>(e >> 32);
                      }
                    });
  return true;
}

// For each vertex, the first vertex at its position, by sorting (bits of x, y, z, then the
// vertex): O(n log n) whatever the positions, where a hash table can be made quadratic by
// positions chosen to collide.
std::vector<std::uint32_t> first_by_sorting(const Mesh& mesh) {
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
  std::vector<std::uint32_t> first(nv);
  for (std::size_t i = 0, run = 0; i < nv; ++i) {
    if (i == 0 || !records[i].same_position(records[i - 1])) run = i;
    first[records[i].v] = records[run].v;
  }
  return first;
}

// The mesh with each position once: the vertices that are first at their position, in order,
// and the triangles re-indexed. Parallel in blocks of vertices: each block's count of kept
// vertices, their offsets, then the kept vertices numbered, then the others by their first.
Mesh renumber(const Mesh& mesh, const std::vector<std::uint32_t>& first) {
  const std::size_t nv = mesh.num_vertices();
  const std::size_t blocks = (nv + kBlock - 1) / kBlock;
  std::vector<std::size_t> offset(blocks + 1, 0);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    std::size_t kept = 0;
    for (std::size_t v = b * kBlock, end = std::min(nv, v + kBlock); v < end; ++v)
      kept += first[v] == v;
    offset[b + 1] = kept;
  });
  for (std::size_t b = 0; b < blocks; ++b) offset[b + 1] += offset[b];
  Mesh out;
  out.positions.resize(3 * offset[blocks]);
  std::vector<std::uint32_t> remap(nv);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    std::size_t next = offset[b];
    for (std::size_t v = b * kBlock, end = std::min(nv, v + kBlock); v < end; ++v) {
      if (first[v] != v) continue;
      std::memcpy(&out.positions[3 * next], &mesh.positions[3 * v], 12);
      remap[v] = static_cast<std::uint32_t>(next++);
    }
  });
  // A vertex's first is itself first at that position (first[first[v]] = first[v]).
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, kBlock),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t v = r.begin(); v != r.end(); ++v)
                        if (first[v] != v) remap[v] = remap[first[v]];
                    });
  out.indices.resize(mesh.indices.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.indices.size(), 3 * kBlock),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i)
                        out.indices[i] = remap[mesh.indices[i]];
                    });
  return out;
}

}  // namespace

Mesh weld_identical_positions(Mesh mesh) {
  const std::size_t nv = mesh.num_vertices();
  if (nv < 2) return mesh;
  std::vector<std::uint32_t> first;
  if (nv >= 0xffffffffu || !first_at_position(mesh, &first)) first = first_by_sorting(mesh);
  // No two positions alike (the common case): the mesh as it is.
  if (first.empty()) return mesh;
  return renumber(mesh, first);
}

}  // namespace lightvol
