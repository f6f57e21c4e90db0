// The mesh formats lightvol reads and writes, named by a path's extension.
#pragma once

#include <string>

#include <lightvol/core/result.h>

namespace lightvol {

enum class MeshFormat { ply, obj, off, stl, drc, glb };

// The format a path's extension names (case-insensitive), or an Error listing the known ones.
Result<MeshFormat> mesh_format_from_path(const std::string& path);

}  // namespace lightvol
