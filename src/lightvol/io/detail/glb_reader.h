// GLB (glTF 2.0 binary), read by the library itself. Draco's glTF decoder (tinygltf underneath)
// trusts the document: fuzzing found it reading freed memory for a buffer view past its buffer and
// crashing on four kinds of dangling reference, and it opens any file a 'uri' names. This reader
// takes the JSON and the BIN chunk alone, checks every reference, accessor and index before using
// it, and hands Draco nothing but the bytes of a KHR_draco_mesh_compression primitive. Internal to
// the library; read_mesh is the entry point.
#pragma once

#include <string>
#include <string_view>

#include <lightvol/core/result.h>
#include <lightvol/io/detail/draco_mesh.h>

namespace lightvol::detail {

// The triangles of the GLB `bytes` (read from `path`, which errors name): every mesh instance of
// the default scene (`scene`, else the first; with no scenes, every mesh once), its positions
// moved by its node's world transform and its triangles flipped where that transform mirrors.
// Primitives are triangles, strips or fans, with POSITION a float VEC3 accessor and optional
// unsigned indices, or KHR_draco_mesh_compression data. Everything else (materials, textures,
// other attributes, 'uri's) is ignored, and no other file is opened. `step` is the coarsest
// Draco quantization step of the positions after their transforms (0 when none is quantized).
// Instances may add up to at most 256 triangles per byte of the file, within the memory budget,
// counted before anything is copied. Any problem is an Error "path: glTF binary: ..." naming the
// object at fault.
Result<DracoMesh> read_glb(std::string_view bytes, const std::string& path);

}  // namespace lightvol::detail
