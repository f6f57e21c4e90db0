// lightvol stats: the triangle-count report. The static grid against the adaptive tessellations
// (collapse and quadtree, side by side) at several error bounds, with the error actually reached,
// the smallest angle and area of the grid triangles and the time of each stage. The counts are
// those `lightvol build --adaptive --max-error E --tessellation T` writes (volume/volume_stats.h).
#include <cmath>
#include <cstdio>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <lightvol/core/text.h>
#include <lightvol/depth/shadow_maps.h>
#include <lightvol/light/light.h>
#include <lightvol/pipeline/stats_report.h>
#include <lightvol/volume/volume_stats.h>

#include "commands.h"
#include "progress.h"

namespace lightvol::cli {
namespace {

struct StatsOptions {
  std::vector<std::string> depth_paths;
  std::string light_path;
  std::string channel;
  std::string max_errors = "0.001,0.01,0.1";
  std::string tessellations = "collapse,quadtree";
  std::string space = "world";
  bool json = false;
  bool csv = false;
  bool quiet = false;
};

// "0.001,0.01" → {0.001, 0.01}; errors name the flag and the bad item.
Result<std::vector<double>> parse_bounds(const std::string& text) {
  std::vector<double> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    // Decimal only (core/text.h parse_decimal): 0x10, inf and nan are not bounds.
    const std::optional<double> v = parse_decimal(item);
    if (!v || *v < 0)
      return Error{"--max-error: '" + item + "' is not a non-negative number in decimal digits"};
    out.push_back(*v);
  }
  if (out.empty()) return Error{"--max-error: give at least one bound, e.g. 0.001,0.01"};
  return out;
}

// "collapse,quadtree" → the tessellations in that order.
Result<std::vector<Tessellation>> parse_tessellations(const std::string& text) {
  std::vector<Tessellation> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (item == "collapse") {
      out.push_back(Tessellation::collapse);
    } else if (item == "quadtree") {
      out.push_back(Tessellation::quadtree);
    } else {
      return Error{"--tessellation: '" + item + "' is not collapse or quadtree"};
    }
  }
  if (out.empty()) return Error{"--tessellation: give at least one of collapse, quadtree"};
  return out;
}

using Rows = std::vector<BoundStats>;

double ratio(const BoundStats& r, const VolumeStats& stats) {
  return double(r.triangles) / double(stats.static_counts().triangles);
}

void print_csv(const VolumeStats& stats, const Rows& rows) {
  using ull = unsigned long long;
  const VolumeCounts st = stats.static_counts();
  if (!stats.omni()) {
    std::printf(
        "mode,max_error,triangles,vertices,max_error_reached,error_pyramid_seconds,balance_seconds,"
        "emit_seconds,tessellation,collapse_seconds,min_angle_degrees,min_area_texels\n");
    std::printf("static,,%llu,%llu,0,,,,,,,\n", ull(st.triangles), ull(st.vertices));
    for (const BoundStats& r : rows)
      std::printf("adaptive,%.9g,%llu,%llu,%.9g,%.6f,%.6f,%.6f,%s,%.6f,%.9g,%.9g\n", r.max_error,
                  ull(r.triangles), ull(r.vertices), r.max_error_reached, stats.pyramid_seconds(),
                  r.balance_seconds, r.emit_seconds, to_string(r.tessellation), r.collapse_seconds,
                  r.min_angle_degrees, r.min_area);
    return;
  }
  std::printf(
      "mode,max_error,triangles,vertices,max_error_reached,px,nx,py,ny,pz,nz,seams,corners,"
      "tessellation,min_angle_degrees,min_area_texels\n");
  std::printf("static,,%llu,%llu,0", ull(st.triangles), ull(st.vertices));
  for (int f = 0; f < kOmniFaces; ++f) std::printf(",%llu", ull(stats.static_face_triangles()));
  std::printf(",%llu,8,,,\n", ull(stats.static_seam_triangles()));
  for (const BoundStats& r : rows) {
    std::printf("adaptive,%.9g,%llu,%llu,%.9g", r.max_error, ull(r.triangles), ull(r.vertices),
                r.max_error_reached);
    for (int f = 0; f < kOmniFaces; ++f) std::printf(",%llu", ull(r.omni.face_triangles[f]));
    std::printf(",%llu,8,%s,%.9g,%.9g\n", ull(r.omni.seam_triangles), to_string(r.tessellation),
                r.min_angle_degrees, r.min_area);
  }
}

void print_table(const StatsOptions& o, const Light& light, const VolumeStats& stats,
                 const Rows& rows) {
  const VolumeCounts st = stats.static_counts();
  const std::string depth(to_string(light.depth));
  if (!stats.omni()) {
    std::printf("%s: %dx%d, %s light, %s depth\n", o.depth_paths.front().c_str(), stats.width(),
                stats.height(), std::string(to_string(light.type)).c_str(), depth.c_str());
    std::printf("static grid: %s triangles, %s vertices\n", thousands(st.triangles).c_str(),
                thousands(st.vertices).c_str());
    std::printf("error pyramid: %.3f s (once for all bounds)\n\n", stats.pyramid_seconds());
    std::printf("%12s %12s %14s %14s %9s %14s %10s %9s %10s %10s %10s\n", "tessellation",
                "max error", "triangles", "vertices", "of static", "reached", "min angle",
                "min area", "balance s", "emit s", "collapse s");
    for (const BoundStats& r : rows)
      std::printf("%12s %12.6g %14s %14s %8.3f%% %14.6g %9.4f° %9.2f %10.3f %10.3f %10.3f\n",
                  to_string(r.tessellation), r.max_error, thousands(r.triangles).c_str(),
                  thousands(r.vertices).c_str(), 100.0 * ratio(r, stats), r.max_error_reached,
                  r.min_angle_degrees, r.min_area, r.balance_seconds, r.emit_seconds,
                  r.collapse_seconds);
    return;
  }
  const int w = stats.width();
  std::printf("%s: 6 faces of %dx%d, omni light, %s depth\n", o.depth_paths.front().c_str(), w, w,
              depth.c_str());
  std::printf("static: %s triangles (%s per face, %s in seams, 8 corners), %s vertices\n",
              thousands(st.triangles).c_str(), thousands(stats.static_face_triangles()).c_str(),
              thousands(stats.static_seam_triangles()).c_str(), thousands(st.vertices).c_str());
  std::printf("error pyramids: %.3f s (once for all bounds)\n\n", stats.pyramid_seconds());
  std::printf("%12s %12s %12s %9s %12s %9s %9s %9s %9s %9s %9s %9s %10s %9s\n", "tessellation",
              "max error", "triangles", "of static", "reached", "px", "nx", "py", "ny", "pz", "nz",
              "seams", "min angle", "min area");
  for (const BoundStats& r : rows) {
    std::printf("%12s %12.6g %12s %8.3f%% %12.6g", to_string(r.tessellation), r.max_error,
                thousands(r.triangles).c_str(), 100.0 * ratio(r, stats), r.max_error_reached);
    for (int f = 0; f < kOmniFaces; ++f)
      std::printf(" %9s", thousands(r.omni.face_triangles[f]).c_str());
    std::printf(" %9s %9.4f° %9.2f\n", thousands(r.omni.seam_triangles).c_str(),
                r.min_angle_degrees, r.min_area);
  }
}

int run_stats(const StatsOptions& o) {
  if (o.json && o.csv) return fail("--json and --csv: choose one");
  Result<std::vector<double>> bounds = parse_bounds(o.max_errors);
  if (!bounds) return fail(bounds.error());
  Result<std::vector<Tessellation>> tessellations = parse_tessellations(o.tessellations);
  if (!tessellations) return fail(tessellations.error());
  Progress progress(o.quiet || o.json || o.csv);

  progress.begin("reading " + o.light_path);
  Result<Light> light = load_light(o.light_path);
  if (!light) return fail(light.error());
  progress.end();

  const bool omni = light->type == LightType::omni;
  progress.begin(omni ? "reading omni faces" : "reading " + o.depth_paths.front());
  DepthReadOptions read_options;
  read_options.channel = o.channel;
  read_options.memory = BuildMemory::stats;  // the error pyramid, not a static volume
  Result<ShadowMaps> maps = read_shadow_maps(*light, o.depth_paths, read_options);
  if (!maps) return fail(maps.error());
  progress.end(size_text(maps->width(), maps->height()) + (omni ? " x 6" : ""));

  progress.begin(omni ? "error pyramids" : "error pyramid");
  Result<VolumeStats> stats =
      VolumeStats::create(*light, *maps, o.space == "light" ? Space::light : Space::world);
  if (!stats) return fail(stats.error());
  progress.end();

  Rows rows;
  for (const Tessellation t : *tessellations)
    for (const double e : *bounds) {
      progress.begin(std::string(to_string(t)) + " at " + std::to_string(e));
      rows.push_back(stats->at(e, t));
      progress.end(thousands(rows.back().triangles) + " triangles");
    }

  if (o.json)
    std::printf("%s\n",
                stats_report_json(*stats, rows, *light, o.light_path, o.depth_paths).c_str());
  else if (o.csv)
    print_csv(*stats, rows);
  else
    print_table(o, *light, *stats, rows);
  return 0;
}

}  // namespace

void add_stats_command(CLI::App& app, Runner* run) {
  auto o = std::make_shared<StatsOptions>();
  CLI::App* cmd = app.add_subcommand("stats",
                                     "Triangle-count report: the static grid against adaptive "
                                     "tessellations at several error bounds.");
  cmd->footer(
      "Example:\n  lightvol stats shadow.exr --light light.json --max-error 0.001,0.01,0.1 --csv\n"
      "For each bound E (world units along the texel rays): the triangles and vertices that\n"
      "'lightvol build --adaptive --max-error E --tessellation T' writes for each tessellation T,\n"
      "the largest error actually reached over all texels, the smallest angle and area of the\n"
      "grid triangles (texel space), and the time of each stage (the error pyramid is built "
      "once).");
  cmd->add_option(
         "depth", o->depth_paths,
         "Depth image: EXR, TIFF, PFM, 16-bit PNG or PGM, HDR, ZFile (omni: six faces, one "
         "{face} path or one W x 6W strip)")
      ->required();
  cmd->add_option("--light", o->light_path, "Light description (LIGHT.json)")->required();
  cmd->add_option("--channel", o->channel, "Channel of a multi-channel image to read (e.g. Z, R)");
  cmd->add_option("--max-error", o->max_errors, "Comma-separated error bounds in world units")
      ->capture_default_str();
  cmd->add_option("--space", o->space, "Frame of the volume (its winding): world or light")
      ->check(CLI::IsMember({"world", "light"}))
      ->capture_default_str();
  cmd->add_option("--tessellation", o->tessellations,
                  "Comma-separated tessellations to compare: collapse, quadtree")
      ->capture_default_str();
  cmd->add_flag("--json", o->json, "Print the report as JSON");
  cmd->add_flag("--csv", o->csv, "Print the report as CSV");
  cmd->add_flag("--quiet,-q", o->quiet, "No progress lines");
  cmd->callback([o, run] { *run = [o] { return run_stats(*o); }; });
}

}  // namespace lightvol::cli
