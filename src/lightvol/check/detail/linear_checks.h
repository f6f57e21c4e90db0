// The pieces of the linear-time checks (check_volume_linear), one file each: edges.cpp (closed,
// edge-manifold, oriented), faces.cpp (degenerate faces, T-junctions), light_proof.cpp (the
// light's non-self-nesting proof); linear.cpp runs them in order. Internal to the check stage.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <lightvol/check/check.h>
#include <lightvol/core/math.h>
#include <lightvol/core/mesh.h>
#include <lightvol/light/light.h>

namespace lightvol::detail {

inline Vec3d position(const Mesh& mesh, std::uint32_t v) {
  return {mesh.positions[3 * v], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2]};
}

// An offender naming `faces` and `vertices`, with the vertices' positions.
inline Offender make_offender(const Mesh& mesh, std::vector<std::int64_t> faces,
                              std::vector<std::uint32_t> vertices) {
  Offender o;
  o.faces = std::move(faces);
  o.vertices = std::move(vertices);
  for (std::uint32_t v : o.vertices) o.positions.push_back(mesh.vertex(v));
  return o;
}

// Face `t` and its three vertices.
inline Offender face_offender(const Mesh& mesh, std::size_t t) {
  const auto [a, b, c] = mesh.triangle(t);
  return make_offender(mesh, {static_cast<std::int64_t>(t)}, {a, b, c});
}

inline CheckResult skipped(std::string_view name, std::string why) {
  CheckResult r;
  r.name = name;
  r.status = CheckStatus::skipped;
  r.detail = std::move(why);
  return r;
}

// Whether `report` holds check `name` and it passed.
inline bool passed(const CheckReport& report, std::string_view name) {
  const CheckResult* c = report.find(name);
  return c && c->status == CheckStatus::passed;
}

struct EdgeResults {
  CheckResult closed, manifold, oriented;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> boundary;  // directed, as in their face
  std::vector<std::int64_t> boundary_faces;
};

// Closed, edge-manifold and oriented, from one linear pass over the edges (edges.cpp); also the
// boundary edges, directed as in their face, for the T-junction check. `mesh`'s indices must be
// in range and it must have fewer than 2^31 triangles.
EdgeResults edge_checks(const Mesh& mesh, int max_offenders);

// Faces with a repeated vertex or a zero cross product (faces.cpp).
CheckResult degenerate_check(const Mesh& mesh, int max_offenders);

// Boundary vertices lying inside boundary edges, within `eps_pos` (the rounding of a coordinate)
// (faces.cpp).
CheckResult t_junction_check(const Mesh& mesh, const EdgeResults& edges, double eps_pos,
                             int max_offenders);

// The light's non-self-nesting proof for a point light (spot, omni: signed solid angles) and a
// directional one (signed projected areas) (light_proof.cpp). `mesh` must be closed,
// edge-manifold and oriented; `quantum` is the positions' quantization step. They set
// `report`'s proof and light sums.
CheckResult nesting_check_point(const Mesh& mesh, const Light& light, double eps_pos,
                                double quantum, int max_offenders, CheckReport* report);
CheckResult nesting_check_directional(const Mesh& mesh, const Light& light, double eps_pos,
                                      double quantum, int max_offenders, CheckReport* report);

}  // namespace lightvol::detail
