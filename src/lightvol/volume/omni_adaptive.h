// The adaptive omni volume (docs/design.md §3 "Adaptive", omni): each cube face tessellated
// adaptively (tessellate/adaptive_grid.h) under one bound, the faces' border vertices made to agree
// across every cube edge, then joined by seam strips and corner triangles like the static omni
// volume.
//
// Across a cube edge both faces carry exactly the same border vertices (each side is forced to
// take the other's, repeated until neither changes; the quadtrees' 2:1 balance propagates the
// forced vertices inward), so each seam is a strip of 2(n − 1) triangles between n facing vertex
// pairs: no T-junctions whatever the levels on either side, and cells facing each other across an
// edge have the same size along it. Closed, outward, star-shaped from the light.
#pragma once

#include <limits>
#include <vector>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>
#include <lightvol/depth/cube_faces.h>
#include <lightvol/light/light.h>
#include <lightvol/volume/adaptive_volume.h>
#include <lightvol/volume/static_volume.h>

namespace lightvol {

// Seam statistics of an adaptive omni build, beyond AdaptiveReport's totals over the six faces.
struct OmniAdaptiveDetail {
  std::uint64_t face_triangles[kOmniFaces] = {};  // each face's grid triangles
  std::uint64_t seam_triangles = 0;               // the twelve seam strips (corners: 8 more)
  int seam_rounds = 0;                            // tessellation rounds until the borders agreed
  int collapse_rounds = 0;  // collapse (default tessellation): rounds until the seams agreed
};

// The six faces' refinement pyramids, built once and reusable for any number of bounds (what
// `lightvol stats` tabulates). Errors name the face's source: unequal faces, an unreachable radial
// depth.
class OmniRefinement {
 public:
  // `cap`: the largest bound build() will be given (RefinementPyramid's cap).
  static Result<OmniRefinement> create(const Light& light, const CubeFaces& cube,
                                       Refinement refinement, Space space,
                                       double cap = std::numeric_limits<double>::infinity());
  double seconds() const { return seconds_; }  // time to build the six pyramids

  // The adaptive omni volume at `bound` (max_error: world units; laplacian: the threshold T).
  // `report` and `detail` as for build_adaptive_omni_volume (report's pyramid_seconds: seconds()).
  // With Tessellation::collapse (max_error only), each face's grid is coarsened after the seams
  // agree, with its four borders locked: both faces of a seam keep the same border vertices.
  // With `memory`, what grows with the tessellation is measured against the memory budget
  // (adaptive_memory_bytes, core/limits.h) as each face's leaves are counted, with the other
  // faces' grids as they stand, before that face's triangles are emitted, and once the seams
  // agree: over it, *memory is the Error and the Mesh is empty.
  Mesh build(double bound, bool measure, AdaptiveReport* report = nullptr,
             OmniAdaptiveDetail* detail = nullptr,
             Tessellation tessellation = Tessellation::collapse, Status* memory = nullptr) const;

 private:
  OmniRefinement(const Light& light, const CubeFaces& cube) : light_(light), cube_(&cube) {}
  Light light_;
  const CubeFaces* cube_;  // not owned: must outlive this object
  std::vector<RefinementPyramid> pyramids_;
  std::vector<Unprojector> faces_;
  double seconds_ = 0;
};

// Builds the adaptive omni volume from six validated equal square faces. `report` (optional)
// receives the totals (grid_triangles and leaves summed over the faces, the largest
// max_error_reached when options.measure); `detail` (optional) the per-face and seam counts.
// Errors name the face's source: unequal faces, an unreachable radial depth; a volume float32
// cannot hold is refused with check_representable's Error (volume/float32_guard.h), naming
// volume.light_source (OmniRefinement::build alone does not run that guard).
Result<Mesh> build_adaptive_omni_volume(const Light& light, const CubeFaces& cube,
                                        const VolumeOptions& volume, const AdaptiveOptions& options,
                                        AdaptiveReport* report = nullptr,
                                        OmniAdaptiveDetail* detail = nullptr);

}  // namespace lightvol
