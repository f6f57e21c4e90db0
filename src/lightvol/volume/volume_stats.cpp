#include <utility>

#include <lightvol/core/check.h>
#include <lightvol/core/stages.h>
#include <lightvol/tessellate/collapse_grid.h>
#include <lightvol/volume/adaptive_volume.h>
#include <lightvol/volume/volume_stats.h>

namespace lightvol {

Result<VolumeStats> VolumeStats::create(const Light& light, const ShadowMaps& maps, Space space) {
  LV_CHECK(maps.omni == (light.type == LightType::omni));
  VolumeStats stats;
  stats.type_ = light.type;
  stats.width_ = maps.width();
  stats.height_ = maps.height();
  if (maps.omni) {
    Result<OmniRefinement> refinement =
        OmniRefinement::create(light, maps.cube, Refinement::max_error, space);
    if (!refinement) return refinement.error();
    stats.omni_.emplace(std::move(*refinement));
    return stats;
  }
  Result<TexelDepths> texels = TexelDepths::create(light, maps.image, 0, maps.source);
  if (!texels) return texels.error();
  stats.pyramid_.emplace(std::move(*texels), Refinement::max_error);
  stats.standard_ = Unprojector(light, maps.width(), maps.height(), 0, space).standard_winding();
  return stats;
}

BoundStats VolumeStats::at(double max_error, Tessellation tessellation) const {
  BoundStats r;
  r.tessellation = tessellation;
  r.max_error = max_error;
  if (omni_) {
    AdaptiveReport report;
    omni_->build(max_error, true, &report, &r.omni, tessellation);
    r.triangles = report.triangles;
    r.vertices = report.vertices;
    r.leaves = report.leaves;
    r.fixup_rounds = report.fixup_rounds;
    r.max_error_reached = report.max_error_reached;
    r.min_angle_degrees = report.min_angle_degrees;
    r.min_area = report.min_area;
    r.collapse_seconds = report.collapse_seconds;
    r.balance_seconds = report.balance_seconds;
    r.emit_seconds = report.emit_seconds;
    r.measure_seconds = report.measure_seconds;
    return r;
  }
  AdaptiveGrid grid = pyramid_->tessellate(max_error, standard_);
  if (tessellation == Tessellation::collapse) {
    CollapseReport collapse;
    grid = collapse_grid(pyramid_->texels(), std::move(grid), max_error, {}, &collapse);
    r.collapse_seconds = collapse.seconds;
  }
  const GridQuality quality = grid_quality(grid);
  r.min_angle_degrees = quality.min_angle_degrees;
  r.min_area = quality.min_area;
  const VolumeCounts counts = adaptive_volume_counts(type_, grid);
  r.triangles = counts.triangles;
  r.vertices = counts.vertices;
  r.leaves = grid.leaves;
  r.fixup_rounds = grid.fixup_rounds;
  r.balance_seconds = grid.balance_seconds;
  r.emit_seconds = grid.emit_seconds;
  StageLog measure;
  measure.begin("measure");
  r.max_error_reached = pyramid_->measure(grid);
  r.measure_seconds = measure.end().seconds;
  return r;
}

double VolumeStats::pyramid_seconds() const {
  return omni_ ? omni_->seconds() : pyramid_->seconds();
}

VolumeCounts VolumeStats::static_counts() const {
  return static_volume_counts(type_, width_, height_);
}

std::uint64_t VolumeStats::static_face_triangles() const {
  return 2ull * static_cast<std::uint64_t>(width_ - 1) * static_cast<std::uint64_t>(height_ - 1);
}

std::uint64_t VolumeStats::static_seam_triangles() const {
  return omni_ ? 24ull * static_cast<std::uint64_t>(width_ - 1) : 0;
}

}  // namespace lightvol
