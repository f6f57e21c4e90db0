// A streaming PLY writer over flat buffers. Internal to src/export.
//
// OpenMesh's PLY writer needs a half-edge kernel behind its exporter and writes value by value;
// for 33-million-triangle volumes we stream the buffers in large blocks instead (the format is a
// header and two arrays). Output: "vertex" with float x y z, "face" with list uchar int
// vertex_indices, as every PLY reader expects.
#pragma once

#include <cstdio>

#include <lightvol/core/mesh_stream.h>
#include <lightvol/core/result.h>

namespace lightvol::detail {

// Writes `mesh` to the open file as it streams. A write error sets *write_failed (errno tells) and
// stops the stream; an Error is the stream's own. Either way the file is to be discarded.
Status write_ply(std::FILE* file, MeshStream& mesh, bool ascii, bool* write_failed);

}  // namespace lightvol::detail
