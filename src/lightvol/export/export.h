// Writing light volumes: PLY (lightvol's own writer, which also streams), OBJ, OFF, STL (OpenMesh's
// writers), DRC (Draco), GLB (glTF 2.0).
#pragma once

#include <string>

#include <lightvol/core/mesh.h>
#include <lightvol/core/mesh_stream.h>
#include <lightvol/core/result.h>
#include <lightvol/io/mesh_format.h>
#include <lightvol/light/light.h>

namespace lightvol {

// What a GLB records beside the mesh. With a light (in the mesh's frame): KHR_lights_punctual on a
// node named "light" at the light's pose (glTF lights shine down their node's −Z): a spot light as
// a spot whose outer cone circumscribes its frustum and whose inner cone is inscribed in it, a
// directional light as directional, an omni light as point; range = the distance to the farthest
// point the light's frustum reaches. The node's extras hold {"lightvol": {"light": L, "medium":
// M}}: L is the light as `parse_light` reads it back (view and projection matrices; omni: position,
// near, far), M the medium JSON given here (omitted when empty), whose intensity is the glTF
// light's.
struct GlbContent {
  const Light* light = nullptr;
  std::string medium_json;  // a medium description (JSON object text), or empty
};

struct ExportOptions {
  bool ascii = false;   // PLY: ASCII instead of binary little-endian; STL: ASCII instead of binary
  int draco_bits = 16;  // DRC and compressed GLB: position quantization bits, 1..30
  bool draco = false;   // GLB: compress with KHR_draco_mesh_compression
  // The volume's light, in the mesh's frame: a lossy encoding must then pass the light's
  // non-self-nesting proof too (check_volume_linear), as `lightvol check --light` will test it.
  const Light* light = nullptr;
  GlbContent glb;  // GLB: the light (and medium) to record in the file
};

// Writes `mesh` to `path` atomically, in the format of its extension. Lossy encodings (DRC,
// compressed GLB) are decoded again and must come back closed, edge-manifold, oriented outward
// and free of collapsed faces (and sound seen from `options.light`), or nothing is written and
// the Error says what broke.
Status write_mesh(const std::string& path, const Mesh& mesh, const ExportOptions& options = {});

// Writes a streamed mesh (core/mesh_stream.h) to `path` atomically as it is produced, without
// holding it: PLY only (binary or ASCII, the same bytes write_mesh writes for the same mesh). An
// Error from the stream, or a write error, leaves nothing at `path`.
Status write_mesh_stream(const std::string& path, MeshStream& mesh,
                         const ExportOptions& options = {});

// Encodes `mesh` as Draco bytes (edgebreaker, `bits` position quantization).
Result<std::string> encode_draco(const Mesh& mesh, int bits);
// Encodes `mesh` as a GLB (glTF 2.0 binary) file's bytes, optionally Draco-compressed, with
// `bufferView.target` set and the light of `content`, if any.
Result<std::string> encode_glb(const Mesh& mesh, bool draco, int bits,
                               const GlbContent& content = {});

}  // namespace lightvol
