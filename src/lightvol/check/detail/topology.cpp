#include <algorithm>
#include <cstring>
#include <sstream>

#include <tbb/parallel_sort.h>

#include <lightvol/check/detail/topology.h>

namespace lightvol {
namespace {

std::string describe_vertex(const Mesh& mesh, std::uint32_t v) {
  std::ostringstream out;
  const auto p = mesh.vertex(v);
  out << v << " (" << p[0] << ", " << p[1] << ", " << p[2] << ")";
  return out.str();
}

}  // namespace

Status check_closed_outward(const Mesh& mesh, const std::string& what) {
  const std::size_t nv = mesh.num_vertices(), nt = mesh.num_triangles();
  if (nt == 0) return Error{what + ": has no triangles"};
  if (nv >= (std::size_t{1} << 31)) return Error{what + ": has too many vertices"};
  for (std::size_t t = 0; t < nt; ++t) {
    const auto [a, b, c] = mesh.triangle(t);
    if (a >= nv || b >= nv || c >= nv)
      return Error{what + ": face " + std::to_string(t) + " indexes a vertex out of range"};
    if (a == b || b == c || a == c)
      return Error{what + ": face " + std::to_string(t) + " is collapsed: vertices " +
                   describe_vertex(mesh, a) + ", " + describe_vertex(mesh, b) + ", " +
                   describe_vertex(mesh, c)};
    const auto pa = mesh.vertex(a), pb = mesh.vertex(b), pc = mesh.vertex(c);
    const double ux = pb[0] - pa[0], uy = pb[1] - pa[1], uz = pb[2] - pa[2];
    const double vx = pc[0] - pa[0], vy = pc[1] - pa[1], vz = pc[2] - pa[2];
    const double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
    if (nx == 0 && ny == 0 && nz == 0)
      return Error{what + ": face " + std::to_string(t) + " has zero area: vertices " +
                   describe_vertex(mesh, a) + ", " + describe_vertex(mesh, b) + ", " +
                   describe_vertex(mesh, c)};
  }
  // Each directed edge a→b as key (min·2^31 + max)·2 + (a < b): after sorting, every undirected
  // edge must appear exactly twice, once in each direction.
  std::vector<std::uint64_t> keys(3 * nt);
  for (std::size_t t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t a = mesh.indices[3 * t + k], b = mesh.indices[3 * t + (k + 1) % 3];
      keys[3 * t + k] = ((std::min(a, b) << 31 | std::max(a, b)) << 1) | (a < b ? 1u : 0u);
    }
  }
  tbb::parallel_sort(keys.begin(), keys.end());
  const auto edge_text = [&](std::uint64_t key) {
    const std::uint64_t e = key >> 1;
    return describe_vertex(mesh, static_cast<std::uint32_t>(e >> 31)) + " - " +
           describe_vertex(mesh, static_cast<std::uint32_t>(e & ((1u << 31) - 1)));
  };
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i;
    while (j < keys.size() && (keys[j] >> 1) == (keys[i] >> 1)) ++j;
    const std::size_t uses = j - i;
    if (uses == 1)
      return Error{what + ": not closed: edge " + edge_text(keys[i]) + " has one face"};
    if (uses > 2)
      return Error{what + ": not edge-manifold: edge " + edge_text(keys[i]) + " has " +
                   std::to_string(uses) + " faces"};
    if (keys[i] == keys[i + 1])
      return Error{what + ": not consistently oriented: edge " + edge_text(keys[i]) +
                   " runs the same way in both its faces"};
    i = j;
  }
  const double volume = signed_volume(mesh);
  if (!(volume > 0))
    return Error{what + ": not oriented outward: signed volume " + std::to_string(volume)};
  return {};
}

}  // namespace lightvol
