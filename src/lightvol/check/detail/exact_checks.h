// lightvol's own self-intersection and bounds-a-volume tests (the default engine of check without
// a light): the same verdicts and pairs as CGAL's (cgal_checks.h), computed without a
// CGAL::Surface_mesh, in parallel. Only exact_checks.cpp includes CGAL (its kernel's filtered
// predicates). Internal to src/check.
#pragma once

#include <cstddef>

#include <lightvol/check/detail/cgal_checks.h>
#include <lightvol/core/mesh.h>

namespace lightvol::detail {

// What cgal_checks computes, with the same results (CgalChecks): the mesh refused for the same
// reasons and named by the same message (a face repeating a vertex, separate fans meeting at a
// vertex), then the pairs of faces that PMP::self_intersections reports: (f, f) for every face
// whose vertices are collinear, and (f, g) for every two other faces whose triangles intersect
// other than along the edge or vertex they share, classified exactly as CGAL's pair test does
// (exact predicates: orientations, CGAL's do_intersect). Counting stops at 10,000 pairs; the first
// `max_pairs` are kept. When `closed` and no pair was found, bounds-a-volume: a single connected
// component bounds a volume whichever way it is oriented (as CGAL's does_bound_a_volume decides:
// inward, it bounds the unbounded volume); several go to CGAL (cgal_bounds_a_volume).
//
// The broad phase: bounding-volume hierarchies over the faces in Morton order, each face's box
// (long faces: its triangle) against the faces after it; faces around hubs (kMinHubDegree) against
// each other by their directions from the hub, as cgal_checks does.
CgalChecks exact_checks(const Mesh& mesh, bool closed, std::size_t max_pairs,
                        double long_face_ratio = kLongFaceRatio,
                        std::size_t min_hub_degree = kMinHubDegree);

// Self-intersection test alone (stopping at the first pair): true when two faces intersect (or a
// face is degenerate) or the mesh is refused. For benchmarks.
bool exact_does_self_intersect(const Mesh& mesh);

}  // namespace lightvol::detail
