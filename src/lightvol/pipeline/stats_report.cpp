#include <nlohmann/json.hpp>

#include <lightvol/depth/cube_faces.h>
#include <lightvol/pipeline/stats_report.h>

namespace lightvol {
namespace {

std::string json_text(const nlohmann::json& j) {
  return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace);
}

double ratio(const BoundStats& r, const VolumeStats& stats) {
  return double(r.triangles) / double(stats.static_counts().triangles);
}

}  // namespace

const char* to_string(Tessellation t) {
  return t == Tessellation::collapse ? "collapse" : "quadtree";
}

std::string stats_report_json(const VolumeStats& stats, const std::vector<BoundStats>& rows,
                              const Light& light, const std::string& light_path,
                              const std::vector<std::string>& depth_paths) {
  const VolumeCounts st = stats.static_counts();
  nlohmann::json adaptive = nlohmann::json::array();
  for (const BoundStats& r : rows) {
    nlohmann::json row = {{"tessellation", to_string(r.tessellation)},
                          {"max_error", r.max_error},
                          {"triangles", r.triangles},
                          {"vertices", r.vertices},
                          {"max_error_reached", r.max_error_reached},
                          {"min_angle_degrees", r.min_angle_degrees},
                          {"min_area_texels", r.min_area},
                          {"leaves", r.leaves},
                          {"ratio_to_static", ratio(r, stats)},
                          {"seconds",
                           {{"balance", r.balance_seconds},
                            {"emit", r.emit_seconds},
                            {"collapse", r.collapse_seconds},
                            {"measure", r.measure_seconds}}}};
    if (stats.omni()) {
      nlohmann::json faces = nlohmann::json::object();
      for (int f = 0; f < kOmniFaces; ++f)
        faces[std::string(omni_face_tag(f))] = r.omni.face_triangles[f];
      row["face_triangles"] = faces;
      row["seam_triangles"] = r.omni.seam_triangles;
      row["corner_triangles"] = 8;
      row["seam_rounds"] = r.omni.seam_rounds;
    } else {
      row["fixup_rounds"] = r.fixup_rounds;
    }
    adaptive.push_back(row);
  }
  nlohmann::json report = {
      {"light",
       {{"path", light_path}, {"type", to_string(light.type)}, {"depth", to_string(light.depth)}}},
      {"width", stats.width()},
      {"height", stats.height()},
      {"static", {{"triangles", st.triangles}, {"vertices", st.vertices}}},
      {"error_pyramid_seconds", stats.pyramid_seconds()},
      {"adaptive", adaptive}};
  if (!stats.omni()) {
    report["input"] = depth_paths.front();
    return json_text(report);
  }
  report["inputs"] = depth_paths;
  report["faces"] = 6;
  report["static"]["face_triangles"] = stats.static_face_triangles();
  report["static"]["seam_triangles"] = stats.static_seam_triangles();
  report["static"]["corner_triangles"] = 8;
  return json_text(report);
}

}  // namespace lightvol
