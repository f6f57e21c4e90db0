// Conversion from Draco's mesh to the flat Mesh, shared by the exporters (which decode what they
// encoded, to verify it) and the reader. Internal to the library: it names Draco types.
#pragma once

#include <draco/mesh/mesh.h>

#include <lightvol/core/mesh.h>

namespace lightvol::detail {

// A decoded Draco mesh as flat buffers: its POSITION attribute (an empty mesh when it has none)
// and its faces, with bit-identical positions welded (Draco may split points by attribute).
Mesh from_draco(const draco::Mesh& in);

}  // namespace lightvol::detail
