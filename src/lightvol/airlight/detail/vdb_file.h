// Density grids from OpenVDB files (`"density": {"type": "vdb", ...}`, docs/design.md §6). OpenVDB
// 10's reader is not hardened against forged files (it trusts the sizes and counts a file states),
// so it runs in lightvol-image (core/detail/image_helper.h), the program that already links it
// through OpenImageIO, with the limits of every decoder there; its side of the conversation is
// vdb_codec.h, the only file of lightvol that includes OpenVDB's headers.
#pragma once

#include <memory>
#include <string>

#include <lightvol/airlight/density.h>
#include <lightvol/core/result.h>

namespace lightvol::detail {

// The scalar grid `grid` of the OpenVDB file at `path`, made dense over its active voxels'
// bounding box, with its background and its linear transform. lightvol's own look first (a
// regular file that starts with OpenVDB's magic number and holds its whole header), then a
// conversation that refuses before anything large is allocated: lightvol-image opens the file,
// finds the grid (its value type must be float or double, its transform linear, its background
// finite and ≥ 0, some voxel active) and sends the box and the transform; lightvol checks the dense
// grid against the memory budget; only then are the voxels made dense, checked (finite, ≥ 0: the
// first bad one is named by its index) and sent. Errors name `path` (and the grid): one line each.
Result<std::shared_ptr<const VoxelGrid>> read_vdb_grid(const std::string& path,
                                                       const std::string& grid);

// The most voxels a grid may have along one axis: a 3D texture's side on every OpenGL 4.5 driver
// is at least 2048; lightvol's renderers upload the grid whole.
constexpr int kMaxGridSide = 2048;

}  // namespace lightvol::detail
