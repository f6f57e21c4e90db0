// Checks of faces and of the boundary: degenerate faces and T-junctions.
#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <lightvol/check/detail/linear_checks.h>

namespace lightvol::detail {

// Faces with a repeated vertex or a cross product of exactly zero (double precision, exact for
// float inputs up to the last rounding).
CheckResult degenerate_check(const Mesh& mesh, int max_offenders) {
  CheckResult r;
  r.name = kCheckDegenerate;
  const std::size_t nt = mesh.num_triangles();
  const auto is_degenerate = [&](std::size_t t) {
    const auto [a, b, c] = mesh.triangle(t);
    if (a == b || b == c || a == c) return true;
    const Vec3d pa = position(mesh, a);
    const Vec3d n = cross(position(mesh, b) - pa, position(mesh, c) - pa);
    return n.x == 0 && n.y == 0 && n.z == 0;
  };
  r.count = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, nt, 1 << 15), std::uint64_t{0},
      [&](const tbb::blocked_range<std::size_t>& range, std::uint64_t n) {
        for (std::size_t t = range.begin(); t != range.end(); ++t) n += is_degenerate(t);
        return n;
      },
      [](std::uint64_t x, std::uint64_t y) { return x + y; });
  for (std::size_t t = 0;
       t < nt && r.offenders.size() < static_cast<std::size_t>(max_offenders) && r.count > 0; ++t)
    if (is_degenerate(t)) r.offenders.push_back(face_offender(mesh, t));
  r.status = r.count == 0 ? CheckStatus::passed : CheckStatus::failed;
  r.detail = std::to_string(r.count) + " faces with zero area or a repeated vertex";
  return r;
}

// T-junctions: a boundary vertex lying inside a boundary edge (strictly between its ends, within
// a millionth of the edge's length plus float rounding). Boundary vertices are binned in a grid
// whose cells are the mean boundary edge length; each edge visits the cells along it.
CheckResult t_junction_check(const Mesh& mesh, const EdgeResults& edges, double eps_pos,
                             int max_offenders) {
  CheckResult r;
  r.name = kCheckTJunctions;
  if (edges.boundary.empty()) {
    r.status = CheckStatus::passed;
    r.detail = "no boundary edges";
    return r;
  }
  std::vector<std::uint32_t> verts;
  double total_length = 0;
  for (const auto& [u, v] : edges.boundary) {
    verts.push_back(u);
    verts.push_back(v);
    total_length += length(position(mesh, v) - position(mesh, u));
  }
  std::sort(verts.begin(), verts.end());
  verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
  const double cell = std::max(total_length / static_cast<double>(edges.boundary.size()), 1e-30);
  // Grid cell of a point; coordinates far beyond the grid's reach are clamped (a cell index must
  // fit an int64), and the hash works in unsigned arithmetic, where overflow wraps.
  const auto axis_cell = [&](double x) {
    const double c = std::floor(x / cell);
    return std::isfinite(c) ? static_cast<std::int64_t>(std::clamp(c, -4.0e15, 4.0e15)) : 0;
  };
  const auto cell_of = [&](Vec3d p) {
    return std::array<std::int64_t, 3>{axis_cell(p.x), axis_cell(p.y), axis_cell(p.z)};
  };
  const auto key_of = [](std::array<std::int64_t, 3> c) {
    return static_cast<std::uint64_t>(c[0]) * 73856093u ^
           static_cast<std::uint64_t>(c[1]) * 19349663u ^
           static_cast<std::uint64_t>(c[2]) * 83492791u;
  };
  std::unordered_multimap<std::uint64_t, std::uint32_t> grid;
  grid.reserve(verts.size());
  for (std::uint32_t v : verts) grid.emplace(key_of(cell_of(position(mesh, v))), v);

  std::unordered_map<std::uint32_t, bool> reported;
  for (std::size_t e = 0; e < edges.boundary.size(); ++e) {
    const auto [u, v] = edges.boundary[e];
    const Vec3d pu = position(mesh, u), pv = position(mesh, v), d = pv - pu;
    const double len2 = dot(d, d);
    if (len2 == 0) continue;
    const double len = std::sqrt(len2);
    const double tol = 1e-6 * len + 4 * eps_pos;
    const int steps = static_cast<int>(std::min(len / cell, 1e7)) + 1;
    std::vector<std::uint64_t> visited;
    for (int s = 0; s <= steps; ++s) {
      const auto c = cell_of(pu + (static_cast<double>(s) / steps) * d);
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            const std::uint64_t key = key_of({c[0] + dx, c[1] + dy, c[2] + dz});
            if (std::find(visited.begin(), visited.end(), key) != visited.end()) continue;
            visited.push_back(key);
            const auto [first, last] = grid.equal_range(key);
            for (auto it = first; it != last; ++it) {
              const std::uint32_t w = it->second;
              if (w == u || w == v || reported.count(w)) continue;
              const Vec3d pw = position(mesh, w);
              const double t = dot(pw - pu, d) / len2;
              if (t * len <= tol || (1 - t) * len <= tol) continue;
              if (length(pw - (pu + t * d)) > tol) continue;
              reported[w] = true;
              if (r.count++ < static_cast<std::uint64_t>(max_offenders))
                r.offenders.push_back(make_offender(mesh, {edges.boundary_faces[e]}, {w, u, v}));
            }
          }
    }
  }
  r.status = r.count == 0 ? CheckStatus::passed : CheckStatus::failed;
  r.detail = std::to_string(r.count) + " vertices lying inside another face's edge";
  return r;
}

}  // namespace lightvol::detail
