// Wavefront OBJ, read by the library itself for positions and faces only. OpenMesh's OBJ reader
// aborts on a face vertex like "/1" (fuzz finding) and follows 'mtllib' to any file relative to
// the OBJ's folder: 'mtllib ../../dev/zero' made it read forever. A light volume or a scene needs
// neither materials nor texture coordinates, so this reader opens nothing but the OBJ.
// Internal to the library; read_mesh is the entry point.
#pragma once

#include <string>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>

namespace lightvol::detail {

// Reads the 'v x y z' and 'f v v v ...' lines of the OBJ file at `path` (face vertices v, v/t,
// v//n or v/t/n; 1-based, negative counting back from the last vertex so far), polygons
// fan-triangulated; every other line is ignored. A malformed vertex or face line, a face of fewer
// than three vertices or naming a missing vertex, or binary data is an Error naming the file and
// the line.
Result<Mesh> read_obj(const std::string& path);

}  // namespace lightvol::detail
