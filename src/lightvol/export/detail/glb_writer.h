// The GLB writer (glTF 2.0 binary) and the Draco mesh both Draco encodings start from.
#pragma once

#include <memory>
#include <string_view>

#include <draco/mesh/mesh.h>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>
#include <lightvol/export/export.h>
#include <lightvol/light/light.h>

namespace lightvol::detail {

// Our flat mesh as a Draco mesh: one point per vertex, positions only.
std::unique_ptr<draco::Mesh> to_draco(const Mesh& mesh);

// `--draco-bits` must lie in 1..30.
Status check_draco_bits(int bits);

// A spot light's frustum as the circular cone of KHR_lights_punctual, in radians from its axis:
// `outer` circumscribes the frustum (the half-angle to its farthest corner: everything the light
// reaches is inside it), `inner` is inscribed (the half-angle to its nearest edge, 0 when the axis
// lies outside an off-centre frustum; just below `outer` when they would be equal).
struct SpotCone {
  double inner = 0, outer = 0;
};
SpotCone spot_cone(const Light& light);

// Draco's GLB with what glTF viewers need beside the mesh: `bufferView.target` on every vertex
// and index buffer view, and, with a light, KHR_lights_punctual on a node at the light's pose with
// lightvol's description of the light (and the medium) in the node's extras. The BIN chunk, and so
// every position, stays as Draco wrote it.
Result<std::string> annotate_glb(std::string_view glb, const GlbContent& content);

}  // namespace lightvol::detail
