#include <algorithm>
#include <cstring>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <lightvol/core/mesh.h>

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
  const float* p = mesh.positions.data();
  const std::uint32_t* idx = mesh.indices.data();
  return tbb::parallel_deterministic_reduce(
             tbb::blocked_range<std::size_t>(0, mesh.num_triangles(), 1 << 16), 0.0,
             [&](const tbb::blocked_range<std::size_t>& r, double acc) {
               for (std::size_t t = r.begin(); t != r.end(); ++t) {
                 const float* a = p + 3 * idx[3 * t];
                 const float* b = p + 3 * idx[3 * t + 1];
                 const float* c = p + 3 * idx[3 * t + 2];
                 const double ax = a[0], ay = a[1], az = a[2];
                 const double bx = b[0], by = b[1], bz = b[2];
                 const double cx = c[0], cy = c[1], cz = c[2];
                 acc +=
                     ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx);
               }
               return acc;
             },
             [](double x, double y) { return x + y; }) /
         6.0;
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
