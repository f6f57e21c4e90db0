// Writing light volumes: PLY, OBJ, OFF, STL (OpenMesh writers), DRC (Draco), GLB (glTF 2.0).
#pragma once

#include <string>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>
#include <lightvol/io/mesh_format.h>
#include <lightvol/light/light.h>

namespace lightvol {

struct ExportOptions {
  bool ascii = false;   // PLY: ASCII instead of binary little-endian; STL: ASCII instead of binary
  int draco_bits = 16;  // DRC and compressed GLB: position quantization bits, 1..30
  bool draco = false;   // GLB: compress with KHR_draco_mesh_compression
  // The volume's light, in the mesh's frame: a lossy encoding must then pass the light's
  // non-self-nesting proof too (check_volume_linear), as `lightvol check --light` will test it.
  const Light* light = nullptr;
};

// Writes `mesh` to `path` atomically, in the format of its extension. Lossy encodings (DRC,
// compressed GLB) are decoded again and must come back closed, edge-manifold, oriented outward
// and free of collapsed faces (and sound seen from `options.light`), or nothing is written and
// the Error says what broke.
Status write_mesh(const std::string& path, const Mesh& mesh, const ExportOptions& options = {});

// Encodes `mesh` as Draco bytes (edgebreaker, `bits` position quantization).
Result<std::string> encode_draco(const Mesh& mesh, int bits);
// Encodes `mesh` as a GLB (glTF 2.0 binary) file's bytes, optionally Draco-compressed.
Result<std::string> encode_glb(const Mesh& mesh, bool draco, int bits);

}  // namespace lightvol
