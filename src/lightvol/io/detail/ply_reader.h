// PLY (ASCII, binary little- and big-endian), read by the library itself. OpenMesh's PLY reader
// trusts its input: fuzzing found it looping forever on four kinds of malformed header and filling
// in 2 GB for one forged list count, and each fix in front of it left the next. This reader parses
// the header fully, bounds every count by the bytes the file has left before allocating, and
// keeps only what a light volume needs. Internal to the library; read_mesh is the entry point.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>

namespace lightvol::detail {

// Reads the vertex element's x, y, z and the face element's vertex_indices (or vertex_index) list,
// fan-triangulated, from the PLY file at `path` of `size` bytes; every other element and property
// is skipped. Elements may come in any order. ASCII files hold one element per line. Any header
// the format does not allow, a count the file cannot hold, a short or long line, a face of fewer
// than three vertices or naming a missing one, and a file that ends early are Errors naming the
// file and the header line, body line or element. `budget(vertices, faces)` is asked, with the
// header's counts, before anything is allocated; its Error is returned.
Result<Mesh> read_ply(const std::string& path, std::uintmax_t size,
                      const std::function<Status(std::uint64_t, std::uint64_t)>& budget);

}  // namespace lightvol::detail
