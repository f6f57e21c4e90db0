// ASCII STL, read by the library itself. OpenMesh's ASCII reader read the three lines after each
// "outer" without checking them: a coordinate "nan", "abc" or "1e39" came back as whatever the
// memory held (7.2e22 one run, 1.8e31 the next) or as infinity. Binary STL is still OpenMesh's,
// in a child process (mesh_reader.cpp).
// Internal to the library; read_mesh is the entry point.
#pragma once

#include <string>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>

namespace lightvol::detail {

// Reads the ASCII STL file at `path`: one or more "solid [name]" … "endsolid [name]" blocks of
// "facet [normal nx ny nz]", "outer loop", three "vertex x y z", "endloop", "endfacet" (keywords
// in any case; the normal is not used). Each corner is a vertex of its own, in file order (the
// caller welds them); a facet with two equal corners is dropped, as OpenMesh's reader (which reads
// binary STL) drops it. A line out of this order, a coordinate that is not a finite float
// (parse_coordinate), binary data, or a file that ends inside a solid is an Error naming the file
// and the line.
Result<Mesh> read_stl_ascii(const std::string& path);

}  // namespace lightvol::detail
