#include <algorithm>
#include <cctype>
#include <filesystem>

#include <lightvol/io/mesh_format.h>

namespace lightvol {

Result<MeshFormat> mesh_format_from_path(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  if (ext == ".ply") return MeshFormat::ply;
  if (ext == ".obj") return MeshFormat::obj;
  if (ext == ".off") return MeshFormat::off;
  if (ext == ".stl") return MeshFormat::stl;
  if (ext == ".drc") return MeshFormat::drc;
  if (ext == ".glb") return MeshFormat::glb;
  return Error{path + ": unknown mesh format '" + ext +
               "' (known: .ply, .obj, .off, .stl, .drc, .glb)"};
}

}  // namespace lightvol
