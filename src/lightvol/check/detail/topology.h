// Linear-time (sort-based) topological checks on flat meshes.
#pragma once

#include <cstdint>
#include <string>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>

namespace lightvol {

// Closed, edge-manifold and consistently oriented: every undirected edge is used by exactly two
// triangles, once in each direction. Also: indices in range, no triangle repeating a vertex
// (collapsed), no zero-area triangle, and a positive signed volume (outward). The Error names
// `what` and the first offending edge or face with its vertices' positions.
Status check_closed_outward(const Mesh& mesh, const std::string& what);

}  // namespace lightvol
