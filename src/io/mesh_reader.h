// Reading triangle meshes: PLY (ASCII and binary), OBJ and text OFF by the library's own strict
// readers, STL (ASCII and binary) through OpenMesh's reader, DRC through Draco, GLB (glTF 2.0
// binary, plain or Draco-compressed) through Draco's glTF decoder.
#pragma once

#include <string>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>

namespace lightvol {

// Reads the mesh at `path`, in the format its extension names (case-insensitive). Polygons with
// more than three vertices are split into fans (v0, vi, vi+1); vertices with bit-identical
// positions are welded (STL stores each triangle's corners separately, Draco may split points).
// Positions are returned as stored, in float precision; no other attribute is kept.
// A missing, empty, truncated or malformed file, an unknown extension, a face that indexes a
// missing vertex or a file with no triangles is an Error naming the file.
Result<Mesh> read_mesh(const std::string& path);

}  // namespace lightvol
