// The triangle-count report of `lightvol stats --json` (docs/formats.md, "Reports"): the static
// grid against adaptive tessellations at several bounds (volume/volume_stats.h).
#pragma once

#include <string>
#include <vector>

#include <lightvol/light/light.h>
#include <lightvol/volume/volume_stats.h>

namespace lightvol {

// "collapse" or "quadtree".
const char* to_string(Tessellation tessellation);

// The report as JSON text (indent 2, no final line break): the light (`light_path`, its type and
// depth encoding), the maps' size and `depth_paths`, the static counts (omni: per face and in the
// seams) and one row per entry of `rows` (VolumeStats::at) with its ratio to the static count.
std::string stats_report_json(const VolumeStats& stats, const std::vector<BoundStats>& rows,
                              const Light& light, const std::string& light_path,
                              const std::vector<std::string>& depth_paths);

}  // namespace lightvol
