// Fuzz target: the mesh readers behind `lightvol check` (PLY, OBJ, OFF, STL, DRC, GLB) and the
// linear checks on whatever they return. The first byte picks the format; the rest is the file.
#include <cstddef>
#include <cstdint>

#include <lightvol/check/check.h>
#include <lightvol/core/check.h>
#include <lightvol/io/mesh_reader.h>

#include "fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static const char* const kExtensions[] = {".ply", ".obj", ".off", ".stl", ".drc", ".glb"};
  const lightvol::fuzz::TempInput file(data + 1, size - 1, kExtensions[data[0] % 6]);
  const lightvol::Result<lightvol::Mesh> mesh = lightvol::read_mesh(file.path());
  if (!mesh) {
    LV_CHECK(mesh.error().message.rfind(file.path(), 0) == 0);
    return 0;
  }
  LV_CHECK(mesh->num_triangles() > 0);
  for (const std::uint32_t i : mesh->indices) LV_CHECK(i < mesh->num_vertices());
  // The linear checks must classify anything the reader accepts, without a light.
  const lightvol::CheckReport report = lightvol::check_volume_linear(*mesh, nullptr);
  LV_CHECK_EQ(report.triangles, mesh->num_triangles());
  return 0;
}
