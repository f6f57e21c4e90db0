// Reading triangle meshes: PLY (ASCII and binary), OBJ and text OFF by the library's own strict
// readers, STL (ASCII and binary) through OpenMesh's reader, DRC through Draco, GLB (glTF 2.0
// binary, plain or Draco-compressed) by the library's own reader, with Draco decoding compressed
// primitives.
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
// `quantization_step`, when given, receives the spacing of the grid Draco quantized the positions
// to (DRC, compressed GLB; after a GLB node's scaling), 0 for positions stored exactly: each lies
// within half a step of where the writer put it, a precision the checks then allow for.
Result<Mesh> read_mesh(const std::string& path, double* quantization_step = nullptr);

}  // namespace lightvol
