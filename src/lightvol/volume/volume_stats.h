// The triangle-count report of `lightvol stats`: the static volume against adaptive volumes at
// several error bounds and tessellations (collapse, quadtree), with the error each actually
// reaches, the smallest angle and area of the grid triangles and the time of each stage. The
// counts are those build_volume writes with VolumeGrid::adaptive and Refinement::max_error.
#pragma once

#include <cstdint>
#include <optional>

#include <lightvol/core/result.h>
#include <lightvol/depth/shadow_maps.h>
#include <lightvol/light/light.h>
#include <lightvol/tessellate/adaptive_grid.h>
#include <lightvol/volume/adaptive_volume.h>
#include <lightvol/volume/omni_adaptive.h>
#include <lightvol/volume/static_volume.h>

namespace lightvol {

// The adaptive volume at one bound and tessellation.
struct BoundStats {
  Tessellation tessellation = Tessellation::collapse;
  double max_error = 0;                        // the bound, world units along the texel rays
  std::uint64_t triangles = 0, vertices = 0;   // of the whole volume, as build_volume writes it
  std::uint64_t leaves = 0;                    // quadtree leaves (all faces of an omni light)
  int fixup_rounds = 0;                        // spot, directional: see AdaptiveGrid
  double max_error_reached = 0;                // the largest error over all texels, world units
  double min_angle_degrees = 0, min_area = 0;  // of the grid triangles, in texel space
  double balance_seconds = 0, emit_seconds = 0, collapse_seconds = 0, measure_seconds = 0;
  OmniAdaptiveDetail omni;  // omni lights: triangles per face and in the seams
};

// The error pyramid(s) of a light's maps, built once, then the volume's counts at any bound.
class VolumeStats {
 public:
  // Builds the pyramid (omni: one per face). `maps` (read_shadow_maps, matching the light) must
  // outlive the object. `space` chooses the winding, as BuildVolumeOptions::space does. Errors
  // name the map's source and the pixel (a radial depth no ray reaches), or the face.
  static Result<VolumeStats> create(const Light& light, const ShadowMaps& maps, Space space);

  // Tessellates at `max_error` (world units) with `tessellation` and measures the error reached.
  // Deterministic.
  BoundStats at(double max_error, Tessellation tessellation = Tessellation::collapse) const;

  bool omni() const { return omni_.has_value(); }
  int width() const { return width_; }  // of one map (omni: one face)
  int height() const { return height_; }
  double pyramid_seconds() const;  // time to build the pyramid(s)
  // The static volume of the same maps, in closed form (static_volume_counts).
  VolumeCounts static_counts() const;
  // Omni: the static volume's triangles per face, and in the twelve seams (the eight corner
  // triangles are in static_counts() only).
  std::uint64_t static_face_triangles() const;
  std::uint64_t static_seam_triangles() const;

 private:
  VolumeStats() = default;
  LightType type_ = LightType::spot;
  int width_ = 0, height_ = 0;
  bool standard_ = true;                      // winding of a spot or directional volume
  std::optional<RefinementPyramid> pyramid_;  // spot, directional
  std::optional<OmniRefinement> omni_;        // omni
};

}  // namespace lightvol
