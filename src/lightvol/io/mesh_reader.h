// Reading triangle meshes: PLY (ASCII and binary), OBJ and text OFF by the library's own strict
// readers, STL (ASCII and binary) through OpenMesh's reader, DRC through Draco, GLB (glTF 2.0
// binary, plain or Draco-compressed) by the library's own reader, with Draco decoding compressed
// primitives.
#pragma once

#include <cstdint>
#include <functional>
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
// The memory budget (core/limits.h) holds for meshes too: the caller's peak for a mesh of V
// vertices and T triangles (`bytes`, the mesh itself included; default mesh_read_bytes) is measured
// against it as soon as the file's counts are known, before they are allocated: from the header
// (PLY, OFF, binary STL; a PLY or OFF face counts as one triangle here, polygons being known only
// once read), and once more from the triangles read (for every format; OBJ and ASCII STL have no
// counts before). Over the budget it is an Error "<path>: <what> N triangles needs about X of
// memory, more than the budget of Y; raise it with set_memory_budget() (e.g. to ZG)".
struct MeshWork {
  std::function<std::uint64_t(std::uint64_t vertices, std::uint64_t triangles)> bytes;
  std::string what = "reading";
};
Result<Mesh> read_mesh(const std::string& path, double* quantization_step = nullptr,
                       const MeshWork& work = {});

// What reading a mesh of V vertices and T triangles holds at its peak: 12 MiB of the process's
// own, the positions and their welded copy (24 bytes a vertex), and the indices (12 a triangle).
std::uint64_t mesh_read_bytes(std::uint64_t vertices, std::uint64_t triangles);

}  // namespace lightvol
