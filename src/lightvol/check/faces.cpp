// The pass over the vertices, and checks of faces and of the boundary: degenerate faces and
// T-junctions.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <unordered_map>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <lightvol/check/detail/linear_checks.h>
#include <lightvol/core/light_side.h>

namespace lightvol::detail {

namespace {

// The vertex pass's partial result over a range of vertices (joined in vertex order).
struct VertexPartial {
  std::array<double, 3> min{}, max{};
  bool any = false;
  std::vector<std::uint32_t> at_light;
  double light_offset = 0;
  VertexPartial join(VertexPartial&& o) && {
    if (!o.any) return std::move(*this);
    if (!any) return std::move(o);
    for (int k = 0; k < 3; ++k)
      min[k] = std::min(min[k], o.min[k]), max[k] = std::max(max[k], o.max[k]);
    if (!o.at_light.empty()) {
      at_light.insert(at_light.end(), o.at_light.begin(), o.at_light.end());
      light_offset = o.light_offset;
    }
    return std::move(*this);
  }
};

}  // namespace

VertexScan scan_vertices(const Mesh& mesh, const Light* light, double quantum) {
  VertexScan out;
  const bool point = light && light->type != LightType::directional;
  const Vec3d light_pos = light ? light->position : Vec3d{};
  out.light_ulp =
      std::ldexp(std::max({std::abs(light_pos.x), std::abs(light_pos.y), std::abs(light_pos.z),
                           static_cast<double>(std::numeric_limits<float>::min())}),
                 -23);
  const double at_light_tol = std::max(4 * out.light_ulp, quantum);
  const float* p = mesh.positions.data();
  VertexPartial all = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, mesh.num_vertices(), 1 << 16), VertexPartial{},
      [&](const tbb::blocked_range<std::size_t>& r, VertexPartial part) {
        if (r.empty()) return part;
        VertexPartial s;
        s.any = true;
        for (int k = 0; k < 3; ++k) s.min[k] = s.max[k] = p[3 * r.begin() + k];
        for (std::size_t v = r.begin(); v != r.end(); ++v) {
          for (int k = 0; k < 3; ++k) {
            const double x = p[3 * v + k];
            s.min[k] = std::min(s.min[k], x);
            s.max[k] = std::max(s.max[k], x);
          }
          if (!point) continue;
          const Vec3d d = Vec3d{p[3 * v], p[3 * v + 1], p[3 * v + 2]} - light_pos;
          const double offset = std::max({std::abs(d.x), std::abs(d.y), std::abs(d.z)});
          if (offset <= at_light_tol) {
            s.at_light.push_back(static_cast<std::uint32_t>(v));
            s.light_offset = offset;
          }
        }
        return std::move(part).join(std::move(s));
      },
      [](VertexPartial x, VertexPartial y) { return std::move(x).join(std::move(y)); });
  if (all.any) out.bounds = {all.min, all.max};
  out.at_light = std::move(all.at_light);
  out.light_offset = all.light_offset;
  return out;
}

// The faces face_pass found degenerate, with the first offenders found again in face order.
CheckResult degenerate_check(const Mesh& mesh, std::uint64_t count, int max_offenders) {
  CheckResult r;
  r.name = kCheckDegenerate;
  r.count = count;
  const std::size_t nt = mesh.num_triangles();
  for (std::size_t t = 0;
       t < nt && r.offenders.size() < static_cast<std::size_t>(max_offenders) && r.count > 0; ++t)
    if (is_degenerate(mesh, t)) r.offenders.push_back(face_offender(mesh, t));
  r.status = r.count == 0 ? CheckStatus::passed : CheckStatus::failed;
  r.detail = std::to_string(r.count) + " faces with zero area or a repeated vertex";
  return r;
}

// T-junctions: a boundary vertex lying inside a boundary edge (strictly between its ends, within
// a millionth of the edge's length plus the float rounding of the three points' own coordinates).
// Boundary vertices are binned in a grid whose cells are the mean boundary edge length; each edge
// visits the cells along it.
CheckResult t_junction_check(const Mesh& mesh, const EdgeResults& edges, int max_offenders) {
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
  std::vector<std::pair<std::uint32_t, std::uint32_t>> offender_edges;
  for (std::size_t e = 0; e < edges.boundary.size(); ++e) {
    const auto [u, v] = edges.boundary[e];
    const Vec3d pu = position(mesh, u), pv = position(mesh, v), d = pv - pu;
    const double len2 = dot(d, d);
    if (len2 == 0) continue;
    const double len = std::sqrt(len2);
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
              const double tol =
                  1e-6 * len + 0.5 * corner_motion(pu, pv, pw);  // 4 ulps of their coordinates
              if (t * len <= tol || (1 - t) * len <= tol) continue;
              if (length(pw - (pu + t * d)) > tol) continue;
              reported[w] = true;
              if (r.count++ < static_cast<std::uint64_t>(max_offenders)) {
                r.offenders.push_back(make_offender(mesh, {}, {w, u, v}));
                offender_edges.emplace_back(u, v);
              }
            }
          }
    }
  }
  // Each boundary edge has one face.
  const std::vector<std::vector<std::int64_t>> faces = faces_of_edges(mesh, offender_edges, 1);
  for (std::size_t k = 0; k < r.offenders.size(); ++k) r.offenders[k].faces = faces[k];
  r.status = r.count == 0 ? CheckStatus::passed : CheckStatus::failed;
  r.detail = std::to_string(r.count) + " vertices lying inside another face's edge";
  return r;
}

}  // namespace lightvol::detail
