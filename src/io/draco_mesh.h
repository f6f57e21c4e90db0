// Conversion from Draco's mesh to the flat Mesh, shared by the exporters (which decode what they
// encoded, to verify it) and the reader. Internal to the library: it names Draco types.
#pragma once

#include <draco/mesh/mesh.h>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>

namespace lightvol::detail {

// A decoded Draco mesh as flat buffers: its POSITION attribute (an empty mesh when it has none)
// and its faces, with bit-identical positions welded (Draco may split points by attribute). A
// POSITION of other than 3 components, a point mapped past the attribute's values or a face
// naming a missing point is an Error (its message names no file: the caller prefixes it).
Result<Mesh> from_draco(const draco::Mesh& in);

}  // namespace lightvol::detail
