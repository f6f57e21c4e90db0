#include <lightvol/core/path.h>
#include <lightvol/io/mesh_format.h>

namespace lightvol {

Result<MeshFormat> mesh_format_from_path(const std::string& path) {
  const std::string ext = lower_extension(path);
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
