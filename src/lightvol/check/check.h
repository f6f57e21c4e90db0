// Validating a light volume (docs/design.md §4): is it closed, edge-manifold, consistently
// oriented, outward, free of degenerate faces, T-junctions and self-intersections, and
// non-self-nesting?
//
// Two ways to prove non-self-nesting (winding number 1 inside, 0 outside), which is what makes
// the signed airlight sum exact:
// - with the light, in linear time: every triangle is seen from the light with the same
//   orientation, so every ray from the light leaves the volume exactly once (see
//   check_volume_linear);
// - without it, with CGAL: no self-intersections, and the mesh bounds a volume (CGAL's nesting
//   test of its connected components).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <lightvol/core/mesh.h>
#include <lightvol/light/light.h>

namespace lightvol {

enum class CheckStatus { passed, failed, skipped };
std::string_view to_string(CheckStatus status);

// One offending element: a face (with its three vertices), an edge (two vertices and the faces
// using it), a T-junction (the vertex, then the edge it lies in), or a pair of intersecting faces.
struct Offender {
  std::vector<std::int64_t> faces;
  std::vector<std::uint32_t> vertices;
  std::vector<std::array<float, 3>> positions;  // of `vertices`, in order
};

struct CheckResult {
  std::string name;  // stable id, see the names below
  CheckStatus status = CheckStatus::skipped;
  std::uint64_t count = 0;          // offending faces, edges or vertices (at least; see detail)
  std::string detail;               // what was measured, or why the check was skipped
  std::vector<Offender> offenders;  // the first few, in mesh order
};

// Check names, in report order.
inline constexpr std::string_view kCheckIndices = "indices";            // all in range
inline constexpr std::string_view kCheckClosed = "closed";              // no boundary edge
inline constexpr std::string_view kCheckManifold = "edge-manifold";     // ≤ 2 faces per edge
inline constexpr std::string_view kCheckOriented = "oriented";          // neighbours agree
inline constexpr std::string_view kCheckOutward = "outward";            // signed volume > 0
inline constexpr std::string_view kCheckDegenerate = "non-degenerate";  // no zero-area face
inline constexpr std::string_view kCheckTJunctions = "no-t-junctions";
inline constexpr std::string_view kCheckSelfIntersections = "no-self-intersections";
inline constexpr std::string_view kCheckBoundsVolume = "bounds-a-volume";
inline constexpr std::string_view kCheckNesting = "non-self-nesting";

// How non-self-nesting was proved (or attempted).
enum class NestingProof {
  none,             // not attempted: no light and no CGAL, or the topology failed first
  solid_angles,     // point light (spot, omni): signed solid angles from the light position
  projected_areas,  // directional light: signed areas projected along the light direction
  cgal,             // no self-intersections + CGAL's bounds-a-volume (winding) test
};
std::string_view to_string(NestingProof proof);

struct CheckReport {
  std::uint64_t vertices = 0;
  std::uint64_t triangles = 0;
  double volume = 0;  // signed, Σ det / 6 (meaningful when closed and oriented)
  Bounds bounds;
  NestingProof proof = NestingProof::none;
  // The light proof's sums: Σ of the per-triangle contributions (steradians for a point light,
  // square units for a directional one) and what a sound volume's must add up to.
  double light_sum = 0;
  double light_expected = 0;
  double quantization_step = 0;  // the positions' quantization the checks allowed for (0: exact)
  std::vector<CheckResult> checks;

  // Sound: no check failed and non-self-nesting was proved.
  bool valid() const;
  const CheckResult* find(std::string_view name) const;
  // "closed: 3 boundary edges, first ..." for the first failed check (empty when valid).
  std::string first_failure() const;
};

// Which code runs the self-intersection and bounds-a-volume tests. Both give the same verdicts
// and pairs (CGAL's definitions, exact predicates); `lightvol` (detail/exact_checks.h) is
// lightvol's own, in parallel and without building a CGAL::Surface_mesh, `cgal` is CGAL's Polygon
// Mesh Processing (detail/cgal_checks.h).
enum class CheckEngine { lightvol, cgal };

struct CheckOptions {
  // With a light: also run the self-intersection and bounds-a-volume tests, which the light
  // proof implies. Without a light they always run.
  bool cgal_with_light = false;
  CheckEngine engine = CheckEngine::lightvol;
  int max_offenders = 5;  // offenders kept per check
  // The spacing of the grid the positions were quantized to (read_mesh reports it for Draco
  // files), 0 for exact ones; see check_volume_linear.
  double quantization_step = 0;
};

// Tolerance: a triangle whose solid angle (or projected area) is within what rounding its
// vertices to float could produce counts as seen edge-on (zero): 8 float ulps of the largest
// coordinate, propagated through the determinant. Quantized positions (`quantization_step` > 0,
// e.g. a Draco file's) widen that by the step, and so the distance within which a vertex counts
// as at the light (a spot volume's apex, which quantization moves off the light) or on the
// directional light's near plane.

// The linear-time checks: indices, closed, edge-manifold, oriented, outward, non-degenerate,
// T-junctions (boundary vertices lying inside boundary edges), and, with a light, the
// non-self-nesting proof, whose frame is the mesh's (a world-space volume needs the world light):
// - spot, omni: every triangle must face away from the light position (positive signed solid
//   angle, Van Oosterom–Strackee), triangles containing the light or seen edge-on counting zero;
//   the solid angles must add up to 4π when the light is inside, or, when the light is a vertex of
//   the mesh (a spot volume's apex), to the solid angle of the cone its incident faces bound.
// - directional: every triangle's area projected along the light direction must be ≥ 0, except
//   faces lying in the light's near plane (normal to `direction`, `near` beyond `position`),
//   where rays enter, which must be ≤ 0; exits must add up to the entries.
// Without a light, non-self-nesting is skipped (CGAL's proof is in check_volume).
// Runs in linear time but for sorting the edge uses at a vertex of more than 8 (O(n log n) at
// worst), in parallel, with the same report for any number of threads.
CheckReport check_volume_linear(const Mesh& mesh, const Light* light, int max_offenders = 5,
                                double quantization_step = 0);

// Everything: the linear checks, then CGAL (Polygon Mesh Processing, exact predicates) for
// self-intersections and bounds-a-volume when there is no light or `cgal_with_light`. CGAL needs
// an edge-manifold, consistently oriented mesh (bounds-a-volume also a closed one without
// self-intersections); otherwise those checks are skipped, the topology having failed already.
CheckReport check_volume(const Mesh& mesh, const Light* light, const CheckOptions& options = {});

// Peak memory of check_volume with `options` (with a light when `with_light`) of a mesh of V
// vertices and T triangles read from a file, the reading included: 12 MiB of the process's own, 24
// bytes a vertex (the positions and their welded copy), and per triangle the indices and the
// checks' working memory: 12 bytes with a light (the linear checks alone), 64 with the default
// engine's self-intersection and bounds-a-volume tests, 256 with CGAL's (`CheckEngine::cgal`: its
// Surface_mesh and AABB tree). Measured peaks of `lightvol check` on 0.25 M- and 1 M-triangle
// volumes (V = T/2) are below it and within 1.25× of it (docs/checks.md). For read_mesh's
// MeshWork, so that a mesh is refused before it is read when the check would exceed the budget.
std::uint64_t check_memory_bytes(std::uint64_t vertices, std::uint64_t triangles, bool with_light,
                                 const CheckOptions& options = {});

}  // namespace lightvol
