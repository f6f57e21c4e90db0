// A light's depth input, whatever its type: one depth image (spot, directional) or six cube faces
// (omni), in the forms of docs/design.md §2. What `lightvol build`, `stats` and `render` read, and
// `shadowmap` writes.
#pragma once

#include <string>
#include <vector>

#include <lightvol/core/result.h>
#include <lightvol/depth/cube_faces.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/light/light.h>

namespace lightvol {

struct ShadowMaps {
  bool omni = false;
  DepthImage image;    // spot, directional: the shadow map
  std::string source;  // spot, directional: what names `image` in errors (its path)
  CubeFaces cube;      // omni: the six faces, each named by cube.sources

  static ShadowMaps planar(DepthImage image, std::string source);
  static ShadowMaps faces(CubeFaces cube);

  // Texels per row and per column of one map (omni: of one face).
  int width() const { return omni ? cube.size() : image.width; }
  int height() const { return omni ? cube.size() : image.height; }
  // The maps as a list, and what names each: one image, or the six faces +X −X +Y −Y +Z −Z
  // (copies, for renderers that take a list).
  std::vector<DepthImage> images() const;
  std::vector<std::string> sources() const;
};

// Reads the depth input of `light` from `paths`: for an omni light read_cube_faces (six paths, one
// path with {face}, or one W × 6W strip); for a spot or directional light exactly one path, read
// with read_depth_image. Errors: those of the readers (naming the file, the face, the pixel), and
// a spot or directional light given other than one path.
Result<ShadowMaps> read_shadow_maps(const Light& light, const std::vector<std::string>& paths,
                                    const DepthReadOptions& options = {});

// Writes `maps` to `path`, atomically, each file with write_depth_image: one image; or the six
// faces, as six files when `path` contains {face} (px nx py ny pz nz), else as one W × 6W strip.
// Returns the paths written. Errors name the file; {face} in the path of a single map is one.
Result<std::vector<std::string>> write_shadow_maps(const std::string& path, const ShadowMaps& maps);

}  // namespace lightvol
