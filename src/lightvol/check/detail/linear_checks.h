// The pieces of the linear-time checks (check_volume_linear), one file each: faces.cpp (the
// vertex pass, degenerate faces, T-junctions), edges.cpp (closed, edge-manifold, oriented),
// light_proof.cpp (the pass over the faces and the light's non-self-nesting proof); linear.cpp
// runs them in order. Internal to the check stage.
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

// One pass over the vertices: their bounds, and with a point light the
// vertices at the light: "at the light" means within the rounding of coordinates there (a few
// float ulps of the light's own position), not of the largest coordinate: a spot volume's near
// plane can lie 10^-6 of the far distance from its apex. Quantized positions are only known to
// within their step (`quantum`) (faces.cpp).
struct VertexScan {
  Bounds bounds;                        // all zeros without vertices
  std::vector<std::uint32_t> at_light;  // all the vertices within the tolerance, in order
  double light_offset = 0;              // of the last of them from the light, max-norm
  double light_ulp = 0;                 // a float ulp of the light position's largest coordinate
};
VertexScan scan_vertices(const Mesh& mesh, const Light* light, double quantum);

struct EdgeResults {
  CheckResult closed, manifold, oriented;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> boundary;  // directed, as in their face
};

// Closed, edge-manifold and oriented, from one linear pass over the edges (edges.cpp); also the
// boundary edges, directed as in their face, for the T-junction check. `mesh`'s indices must be
// in range and it must have fewer than 2^31 triangles.
EdgeResults edge_checks(const Mesh& mesh, int max_offenders);

// For each edge (two vertices, in either order), the faces using it in face order, a face as
// many times as it uses the edge, at most `limit` (edges.cpp): one pass over the faces.
std::vector<std::vector<std::int64_t>> faces_of_edges(
    const Mesh& mesh, const std::vector<std::pair<std::uint32_t, std::uint32_t>>& edges,
    std::size_t limit);

// A face with a repeated vertex or a cross product of exactly zero (double precision, exact for
// float inputs up to the last rounding).
inline bool is_degenerate(const Mesh& mesh, std::size_t t) {
  const auto [a, b, c] = mesh.triangle(t);
  if (a == b || b == c || a == c) return true;
  const Vec3d pa = position(mesh, a);
  const Vec3d n = cross(position(mesh, b) - pa, position(mesh, c) - pa);
  return n.x == 0 && n.y == 0 && n.z == 0;
}

// The `count` degenerate faces, with the first offenders (faces.cpp).
CheckResult degenerate_check(const Mesh& mesh, std::uint64_t count, int max_offenders);

// Boundary vertices lying inside boundary edges, within the float rounding of the edge's and the
// vertex's own coordinates (faces.cpp).
CheckResult t_junction_check(const Mesh& mesh, const EdgeResults& edges, int max_offenders);

// Per-face sums of the light proof.
struct LightSums {
  double positive = 0;  // Σ of the contributions counted
  double negative = 0;  // Σ |contribution| of faces on the wrong side (offenders)
  double source = 0;    // directional: Σ |area| of near-plane faces facing the light
  double zeroed = 0;    // Σ |contribution| of faces counted as edge-on
  std::uint64_t wrong = 0;
  LightSums operator+(const LightSums& o) const {
    return {positive + o.positive, negative + o.negative, source + o.source, zeroed + o.zeroed,
            wrong + o.wrong};
  }
};

// How the face pass sees the faces from the light (light_proof.cpp): not at all (no light, or
// the topology failed, or several vertices lie at the light), from a point (spot, omni), or
// along a direction.
struct LightView {
  enum class Kind { none, point, directional } kind = Kind::none;
  // A face within its corners' motion of edge-on counts zero: corner_motion of the face's own
  // corners (core/light_side.h) plus this, the positions' quantization step and the rounding of
  // the view's own arithmetic (frame_motion of the eye, or of the near plane's origin).
  double extra = 0;
  // Point: the eye (the light, or the vertex at it) and that vertex (~0u: none).
  Vec3d eye;
  std::uint32_t apex = ~0u;
  // Directional: the unit direction and the near plane's origin (a face's corners lie in the
  // plane within the face's motion).
  Vec3d f, origin;
  // Point: most faces decided in vectorized lanes (light_proof.cpp; where vector_lanes(),
  // core/buffer.h), the others one by one; false: every face one by one (the same sums to the
  // bit: the tests compare the two).
  bool lanes = true;
};
LightView point_view(const Mesh& mesh, const Light& light, const VertexScan& scan, double quantum);
LightView directional_view(const Light& light, double quantum);

// The per-face sums of one parallel pass over the faces: the signed volume (exactly as
// signed_volume sums it), the degenerate faces, and with a view the light's sums and the faces
// around the apex.
struct FaceSums {
  double det = 0;  // Σ det(a, b, c) = 6 × the signed volume
  std::uint64_t degenerate = 0;
  LightSums light;
  // For each corner of a face at the apex: the next and the previous vertex, in face order.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> apex_link;
};
FaceSums face_pass(const Mesh& mesh, const LightView& view);

// The light's non-self-nesting proof for a point light (spot, omni: signed solid angles) and a
// directional one (signed projected areas) (light_proof.cpp), from the face pass's sums. `mesh`
// must be closed, edge-manifold and oriented; `quantum` is the positions' quantization step.
// They set `report`'s proof and light sums.
CheckResult nesting_check_point(const Mesh& mesh, const VertexScan& scan, const LightView& view,
                                const FaceSums& sums, double quantum, int max_offenders,
                                CheckReport* report);
CheckResult nesting_check_directional(const Mesh& mesh, const LightView& view, const FaceSums& sums,
                                      int max_offenders, CheckReport* report);

}  // namespace lightvol::detail
