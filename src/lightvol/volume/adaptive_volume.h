// The adaptive light volume (docs/design.md §3 "Adaptive"): the adaptive grid of one depth image,
// closed like the static volume (spot fan, directional walls and cap) through exactly its border
// vertices.
#pragma once

#include <cstdint>
#include <string>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/light/light.h>
#include <lightvol/tessellate/adaptive_grid.h>
#include <lightvol/volume/static_volume.h>

namespace lightvol {

// How a max_error grid is triangulated: the restricted quadtree of RefinementPyramid, or that
// quadtree coarsened by exact-verified collapses (collapse_grid.h; the default). Both meet the
// bound at every texel; Refinement::laplacian has no bound to verify and always uses the quadtree.
enum class Tessellation { quadtree, collapse };

struct AdaptiveOptions {
  Refinement refinement = Refinement::max_error;
  Tessellation tessellation = Tessellation::collapse;
  double max_error = 0.001;  // world units, for Refinement::max_error (> 0)
  double threshold = 0.01;   // |Laplacian of window depth|, for Refinement::laplacian (≥ 0)
  bool measure = false;      // also measure the largest error reached over all texels
};

// What a build did: counts, the reached error and the time of each stage.
struct AdaptiveReport {
  std::uint64_t vertices = 0, triangles = 0;  // of the whole volume, as written
  std::uint64_t grid_triangles = 0, leaves = 0;
  int fixup_rounds = 0;
  std::uint64_t quadtree_triangles = 0;  // of the grid(s) before the collapses (= grid_triangles
                                         // with Tessellation::quadtree)
  std::uint64_t collapses = 0;
  double max_error_reached = -1;  // world units; −1 when not measured
  double min_angle_degrees = 0;   // the grid triangles' smallest angle and area, in texel space
  double min_area = 0;
  double pyramid_seconds = 0, balance_seconds = 0, emit_seconds = 0, collapse_seconds = 0,
         measure_seconds = 0, assemble_seconds = 0;
};

// Vertex and triangle counts of the volume assemble_adaptive_volume makes from `grid`.
VolumeCounts adaptive_volume_counts(LightType type, const AdaptiveGrid& grid);

// Positions the grid's vertices on their texel rays (Unprojector, as the static volume does),
// appends its triangles and closes it. spot and directional lights. Vertices: the grid's, in
// texel order, then the closing's. Errors name `source` and the pixel (unreachable radial depth).
Result<Mesh> assemble_adaptive_volume(const Light& light, const DepthImage& depth,
                                      const AdaptiveGrid& grid, const VolumeOptions& options,
                                      const std::string& source);

// The whole adaptive build: texel depths, pyramid, tessellation, assembly. Closed, oriented
// outward, without T-junctions; in max_error mode every texel's point lies within
// options.max_error world units of its ray's point on the volume. `report` is optional. A volume
// float32 cannot hold is refused with check_representable's Error (volume/float32_guard.h), naming
// volume.light_source; assemble_adaptive_volume alone does not run that guard.
// The bound `options` uses (max_error or threshold, per its refinement), or an error naming the
// option when it is negative, NaN or infinite.
Result<double> adaptive_bound(const AdaptiveOptions& options);

Result<Mesh> build_adaptive_volume(const Light& light, const DepthImage& depth,
                                   const VolumeOptions& volume, const AdaptiveOptions& options,
                                   const std::string& source, AdaptiveReport* report = nullptr);

}  // namespace lightvol
