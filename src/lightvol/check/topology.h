// "Closed, edge-manifold, consistently oriented, outward" as one yes-or-no answer with a message:
// the linear checks of check.h without a light.
#pragma once

#include <string>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>

namespace lightvol {

// Closed, edge-manifold, consistently oriented and outward, without a light: the linear checks
// (check_volume_linear with no light) all pass, i.e. also indices in range, at least one
// triangle, no degenerate face (repeated vertex or zero area) and no T-junction. Otherwise an
// Error "what: <the first failed check, as CheckReport::first_failure>". The exporters verify a
// lossy encoding with it when they have no light.
Status check_closed_outward(const Mesh& mesh, const std::string& what);

}  // namespace lightvol
