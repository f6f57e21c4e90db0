// Decoding mesh bytes held in memory (DRC, GLB), as read_mesh decodes such files.
#pragma once

#include <string>
#include <string_view>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>
#include <lightvol/io/mesh_format.h>

namespace lightvol {

// A mesh decoded from bytes in memory, and the spacing of the grid Draco quantized its positions
// to (0 when they were stored exactly; see read_mesh's `quantization_step`).
struct DecodedMesh {
  Mesh mesh;
  double quantization_step = 0;
};

// Decodes the bytes of a DRC or GLB file (`format`; any other format is an Error) as read_mesh
// decodes such a file (Draco in a child process, GLB by the library's own reader), without
// read_mesh's final checks and welding across GLB primitives (Draco's points are welded). `what`
// names the bytes in errors, as read_mesh names the file ("what: not a Draco mesh: ...", "what:
// glTF binary: ..."). The exporters decode what they encoded with it, to verify a lossy encoding
// before writing it.
Result<DecodedMesh> decode_mesh_bytes(std::string_view bytes, MeshFormat format,
                                      const std::string& what);

}  // namespace lightvol
