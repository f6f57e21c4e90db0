// CGAL's checks behind a CGAL-free interface: CGAL stays in cgal_checks.cpp, the one translation
// unit that converts the flat Mesh to a CGAL::Surface_mesh. Internal to src/check.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <lightvol/core/mesh.h>

namespace lightvol::detail {

struct CgalChecks {
  bool built = false;   // the mesh converted to a Surface_mesh (edge-manifold and oriented)
  std::string why_not;  // why it did not
  std::uint64_t intersecting_pairs = 0;
  bool pairs_truncated = false;  // stopped counting at the limit
  std::vector<std::pair<std::uint32_t, std::uint32_t>> first_pairs;  // face indices
  bool ran_volume_test = false;  // closed and free of self-intersections
  bool bounds_a_volume = false;
  std::size_t components = 0;
};

// Faces whose bounding box is longer than this many times the median face's go through an AABB
// tree instead of CGAL's box sweep, for which they are quadratic (a spot volume's fan).
inline constexpr double kLongFaceRatio = 8;

// Vertices with at least this many faces, and at least √(faces) of them, are hubs: the faces around
// them are tested through their directions from the hub, not through boxes that all contain it
// (a spot volume's apex, a directional cap's centre, a hostile mesh whose faces share one vertex).
inline constexpr std::size_t kMinHubDegree = 33;

// Self-intersections (PMP::self_intersections, parallel with TBB, exact predicates; long faces
// against an AABB tree and faces around hubs by direction, with the same pair test), and when
// `closed` and none were found, PMP::does_bound_a_volume. Stops counting intersecting pairs at
// 10,000; keeps the first `max_pairs`.
CgalChecks cgal_checks(const Mesh& mesh, bool closed, std::size_t max_pairs,
                       double long_face_ratio = kLongFaceRatio,
                       std::size_t min_hub_degree = kMinHubDegree);

// Self-intersection test alone (as in cgal_checks, stopping at the first pair): true when two faces
// intersect other than along shared edges and vertices, or when `mesh` is not edge-manifold and
// oriented. For benchmarks.
bool cgal_does_self_intersect(const Mesh& mesh, double long_face_ratio = kLongFaceRatio,
                              std::size_t min_hub_degree = kMinHubDegree);

// CGAL's own parallel test, PMP::does_self_intersect<Parallel_if_available_tag> on the whole
// Surface_mesh (no long-face or hub routes), true also when the mesh cannot be converted. For
// benchmarks and as the tests' oracle.
bool cgal_pmp_does_self_intersect(const Mesh& mesh);

// CGAL's PMP::self_intersections<Parallel_if_available_tag> on the whole Surface_mesh: every pair,
// sorted (f < g, or f == g for a degenerate face). Empty when the mesh cannot be converted. The
// tests' oracle.
std::vector<std::pair<std::uint32_t, std::uint32_t>> cgal_pmp_self_intersections(const Mesh& mesh);

// PMP::does_bound_a_volume of a closed, edge-manifold, oriented mesh without self-intersections
// (exact_checks' route for several connected components).
bool cgal_bounds_a_volume(const Mesh& mesh);

}  // namespace lightvol::detail
