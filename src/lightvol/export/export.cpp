#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/System/omstream.hh>
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>

#include <lightvol/check/check.h>
#include <lightvol/check/topology.h>
#include <lightvol/core/atomic_file.h>
#include <lightvol/core/check.h>
#include <lightvol/export/detail/flat_exporter.h>
#include <lightvol/export/detail/glb_writer.h>
#include <lightvol/export/detail/ply_writer.h>
#include <lightvol/export/export.h>
#include <lightvol/io/mesh_decode.h>

namespace lightvol {

namespace {

// What a lossy encoding must preserve: the same number of faces, and a sound volume, proved with
// the light when there is one, allowing for the quantization step (as `check` does on the file).
Status verify_decoded(const Mesh& original, const DecodedMesh& decoded, const std::string& what,
                      const ExportOptions& options) {
  if (decoded.mesh.num_triangles() != original.num_triangles())
    return Error{what + ": " +
                 std::to_string(original.num_triangles() - decoded.mesh.num_triangles()) +
                 " faces were lost (collapsed by quantization); raise ExportOptions::draco_bits"};
  if (options.light) {
    const CheckReport report =
        check_volume_linear(decoded.mesh, options.light, 1, decoded.quantization_step);
    if (!report.valid())
      return Error{what + ": " + report.first_failure() + "; raise ExportOptions::draco_bits"};
    return {};
  }
  if (Status s = check_closed_outward(decoded.mesh, what); !s)
    return Error{s.error().message + "; raise ExportOptions::draco_bits"};
  return {};
}

Status write_with_openmesh(const std::string& path, const std::string& temp, MeshFormat format,
                           const Mesh& mesh, const ExportOptions& options) {
  OpenMesh::IO::Options opts;
  std::string ext;
  switch (format) {
    case MeshFormat::stl:
      ext = "stl";
      if (!options.ascii) opts += OpenMesh::IO::Options::Binary;
      break;
    case MeshFormat::obj:
      ext = "obj";
      break;
    case MeshFormat::off:
      ext = "off";
      break;
    default:
      LV_CHECK(false);
  }
  // OpenMesh chats on its log streams; a command-line tool speaks for itself.
  omlog().disable();
  omout().disable();
  // The temporary exists (write_file_atomically made it): opened without creating it, so that a
  // signal's cleanup that unlinked it while this thread was about to open it is not undone.
  std::ofstream out(temp, std::ios::binary | std::ios::in | std::ios::out);
  if (!out) return Error{path + ": cannot create file: " + std::strerror(errno)};
  std::vector<char> buffer(1 << 20);
  out.rdbuf()->pubsetbuf(buffer.data(), static_cast<std::streamsize>(buffer.size()));
  detail::FlatExporter exporter(mesh);
  // Nine significant digits round-trip every float exactly in the ASCII formats.
  if (!OpenMesh::IO::IOManager().write(out, ext, exporter, opts, 9))
    return Error{path + ": OpenMesh could not write the mesh"};
  out.close();
  if (!out) return Error{path + ": write failed: " + std::strerror(errno)};
  return {};
}

Status write_ply_file(const std::string& path, MeshStream& mesh, const ExportOptions& options) {
  return write_file_atomically(path, [&](const std::string& temp) -> Status {
    std::FILE* f = std::fopen(temp.c_str(), "r+b");  // exists and is empty: never re-created
    if (!f) return Error{path + ": cannot create file: " + std::strerror(errno)};
    bool write_failed = false;
    const Status streamed = detail::write_ply(f, mesh, options.ascii, &write_failed);
    const int saved = errno;
    const bool closed = std::fclose(f) == 0;
    if (!streamed) return streamed;
    if (write_failed || !closed)
      return Error{path + ": write failed: " + std::strerror(write_failed ? saved : errno)};
    return {};
  });
}

}  // namespace

Result<std::string> encode_draco(const Mesh& mesh, int bits) {
  if (Status s = detail::check_draco_bits(bits); !s) return s.error();
  const auto dm = detail::to_draco(mesh);
  draco::Encoder encoder;
  encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, bits);
  encoder.SetSpeedOptions(5, 5);
  draco::EncoderBuffer buffer;
  const draco::Status status = encoder.EncodeMeshToBuffer(*dm, &buffer);
  if (!status.ok()) return Error{"Draco encoding failed: " + status.error_msg_string()};
  return std::string(buffer.data(), buffer.size());
}

Status write_mesh(const std::string& path, const Mesh& mesh, const ExportOptions& options) {
  const Result<MeshFormat> format = mesh_format_from_path(path);
  if (!format) return format.error();

  switch (*format) {
    case MeshFormat::drc:
    case MeshFormat::glb: {
      const bool lossy = *format == MeshFormat::drc || options.draco;
      Result<std::string> bytes =
          *format == MeshFormat::drc
              ? encode_draco(mesh, options.draco_bits)
              : encode_glb(mesh, options.draco, options.draco_bits, options.glb);
      if (!bytes) return Error{path + ": " + bytes.error().message};
      if (lossy) {
        const Result<DecodedMesh> back = decode_mesh_bytes(*bytes, *format, path);
        if (!back) return Error{back.error().message + " (decoding what was just encoded)"};
        if (Status s = verify_decoded(mesh, *back, path + " (decoded)", options); !s) return s;
      }
      return write_bytes_atomically(path, *bytes);
    }
    case MeshFormat::ply: {
      MeshBufferStream stream(mesh);
      return write_ply_file(path, stream, options);
    }
    default:
      return write_file_atomically(path, [&](const std::string& temp) {
        return write_with_openmesh(path, temp, *format, mesh, options);
      });
  }
}

Status write_mesh_stream(const std::string& path, MeshStream& mesh, const ExportOptions& options) {
  const Result<MeshFormat> format = mesh_format_from_path(path);
  if (!format) return format.error();
  if (*format != MeshFormat::ply)
    return Error{path + ": a streamed mesh is written as .ply only (write_mesh takes the others)"};
  return write_ply_file(path, mesh, options);
}

}  // namespace lightvol
