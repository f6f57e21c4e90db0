// lightvol stats: the triangle-count report. The static grid against the adaptive tessellation at
// several error bounds, with the error actually reached and the time of each stage. The counts are
// those `lightvol build --adaptive --max-error E` writes (same library calls).
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <lightvol/depth/cube_faces.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/light/light.h>
#include <lightvol/volume/adaptive_volume.h>
#include <lightvol/volume/omni_adaptive.h>
#include <lightvol/volume/static_volume.h>

#include "commands.h"
#include "progress.h"

namespace lightvol::cli {
namespace {

struct StatsOptions {
  std::vector<std::string> depth_paths;
  std::string light_path;
  std::string channel;
  std::string max_errors = "0.001,0.01,0.1";
  std::string space = "world";
  bool json = false;
  bool csv = false;
  bool quiet = false;
};

struct Row {
  double max_error = 0;
  std::uint64_t triangles = 0, vertices = 0, leaves = 0;
  int fixup_rounds = 0;
  double reached = 0, balance = 0, emit = 0, measure = 0;
};

// "0.001,0.01" → {0.001, 0.01}; errors name the flag and the bad item.
Result<std::vector<double>> parse_bounds(const std::string& text) {
  std::vector<double> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    std::size_t used = 0;
    double v = 0;
    try {
      v = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !(v >= 0))
      return Error{"--max-error: '" + item + "' is not a non-negative number"};
    out.push_back(v);
  }
  if (out.empty()) return Error{"--max-error: give at least one bound, e.g. 0.001,0.01"};
  return out;
}

// Omni lights: the same table over the whole cube, with each bound's triangles per face and in the
// seams (the twelve strips; the eight corner triangles are in the totals).
int run_stats_omni(const StatsOptions& o, const Light& light, const std::vector<double>& bounds,
                   Progress& progress) {
  progress.begin("reading omni faces");
  Result<CubeFaces> cube = read_cube_faces(o.depth_paths, {o.channel});
  if (!cube) return fail(cube.error().message);
  const int w = cube->size();
  progress.end(std::to_string(w) + "x" + std::to_string(w) + " x 6");
  progress.begin("error pyramids");
  Result<OmniRefinement> refinement = OmniRefinement::create(
      light, *cube, Refinement::max_error, o.space == "light" ? Space::light : Space::world);
  if (!refinement) return fail(refinement.error().message);
  progress.end();

  std::vector<Row> rows;
  std::vector<OmniAdaptiveDetail> details;
  for (const double e : bounds) {
    progress.begin("tessellating at " + std::to_string(e));
    AdaptiveReport report;
    OmniAdaptiveDetail detail;
    const Mesh mesh = refinement->build(e, true, &report, &detail);
    Row r;
    r.max_error = e;
    r.triangles = report.triangles;
    r.vertices = report.vertices;
    r.leaves = report.leaves;
    r.fixup_rounds = report.fixup_rounds;
    r.reached = report.max_error_reached;
    r.balance = report.balance_seconds;
    r.emit = report.emit_seconds;
    r.measure = report.measure_seconds;
    rows.push_back(r);
    details.push_back(detail);
    progress.end(thousands(r.triangles) + " triangles");
  }
  const VolumeCounts st = static_volume_counts(LightType::omni, w, w);
  const std::uint64_t static_face = 2ull * (w - 1) * (w - 1), static_seams = 24ull * (w - 1);

  if (o.json) {
    nlohmann::json adaptive = nlohmann::json::array();
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const Row& r = rows[i];
      nlohmann::json faces = nlohmann::json::object();
      for (int f = 0; f < kOmniFaces; ++f)
        faces[std::string(omni_face_tag(f))] = details[i].face_triangles[f];
      adaptive.push_back(
          {{"max_error", r.max_error},
           {"triangles", r.triangles},
           {"vertices", r.vertices},
           {"max_error_reached", r.reached},
           {"leaves", r.leaves},
           {"ratio_to_static", double(r.triangles) / double(st.triangles)},
           {"face_triangles", faces},
           {"seam_triangles", details[i].seam_triangles},
           {"corner_triangles", 8},
           {"seam_rounds", details[i].seam_rounds},
           {"seconds", {{"balance", r.balance}, {"emit", r.emit}, {"measure", r.measure}}}});
    }
    const nlohmann::json report = {
        {"inputs", o.depth_paths},
        {"light", {{"path", o.light_path}, {"type", "omni"}, {"depth", to_string(light.depth)}}},
        {"width", w},
        {"height", w},
        {"faces", 6},
        {"static",
         {{"triangles", st.triangles},
          {"vertices", st.vertices},
          {"face_triangles", static_face},
          {"seam_triangles", static_seams},
          {"corner_triangles", 8}}},
        {"error_pyramid_seconds", refinement->seconds()},
        {"adaptive", adaptive}};
    std::printf("%s\n", report.dump(2).c_str());
    return 0;
  }
  if (o.csv) {
    std::printf(
        "mode,max_error,triangles,vertices,max_error_reached,px,nx,py,ny,pz,nz,seams,corners\n");
    std::printf("static,,%llu,%llu,0", static_cast<unsigned long long>(st.triangles),
                static_cast<unsigned long long>(st.vertices));
    for (int f = 0; f < kOmniFaces; ++f)
      std::printf(",%llu", static_cast<unsigned long long>(static_face));
    std::printf(",%llu,8\n", static_cast<unsigned long long>(static_seams));
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const Row& r = rows[i];
      std::printf("adaptive,%.9g,%llu,%llu,%.9g", r.max_error,
                  static_cast<unsigned long long>(r.triangles),
                  static_cast<unsigned long long>(r.vertices), r.reached);
      for (int f = 0; f < kOmniFaces; ++f)
        std::printf(",%llu", static_cast<unsigned long long>(details[i].face_triangles[f]));
      std::printf(",%llu,8\n", static_cast<unsigned long long>(details[i].seam_triangles));
    }
    return 0;
  }
  std::printf("%s: 6 faces of %dx%d, omni light, %s depth\n", o.depth_paths.front().c_str(), w, w,
              std::string(to_string(light.depth)).c_str());
  std::printf("static: %s triangles (%s per face, %s in seams, 8 corners), %s vertices\n",
              thousands(st.triangles).c_str(), thousands(static_face).c_str(),
              thousands(static_seams).c_str(), thousands(st.vertices).c_str());
  std::printf("error pyramids: %.3f s (once for all bounds)\n\n", refinement->seconds());
  std::printf("%12s %12s %9s %12s %9s %9s %9s %9s %9s %9s %9s\n", "max error", "triangles",
              "of static", "reached", "px", "nx", "py", "ny", "pz", "nz", "seams");
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    std::printf("%12.6g %12s %8.3f%% %12.6g", r.max_error, thousands(r.triangles).c_str(),
                100.0 * double(r.triangles) / double(st.triangles), r.reached);
    for (int f = 0; f < kOmniFaces; ++f)
      std::printf(" %9s", thousands(details[i].face_triangles[f]).c_str());
    std::printf(" %9s\n", thousands(details[i].seam_triangles).c_str());
  }
  return 0;
}

int run_stats(const StatsOptions& o) {
  if (o.json && o.csv) return fail("--json and --csv: choose one");
  Result<std::vector<double>> bounds = parse_bounds(o.max_errors);
  if (!bounds) return fail(bounds.error().message);
  Progress progress(o.quiet || o.json || o.csv);

  progress.begin("reading " + o.light_path);
  Result<Light> light = load_light(o.light_path);
  if (!light) return fail(light.error().message);
  progress.end();
  if (light->type == LightType::omni) return run_stats_omni(o, *light, *bounds, progress);
  if (o.depth_paths.size() != 1)
    return fail("a " + std::string(to_string(light->type)) + " light takes one depth image, got " +
                std::to_string(o.depth_paths.size()));
  const std::string& depth_path = o.depth_paths.front();
  progress.begin("reading " + depth_path);
  Result<DepthImage> depth = read_depth_image(depth_path, {o.channel});
  if (!depth) return fail(depth.error().message);
  progress.end(std::to_string(depth->width) + "x" + std::to_string(depth->height));

  progress.begin("error pyramid");
  Result<TexelDepths> texels = TexelDepths::create(*light, *depth, 0, depth_path);
  if (!texels) return fail(texels.error().message);
  const RefinementPyramid pyramid(std::move(*texels), Refinement::max_error);
  progress.end();
  const Space space = o.space == "light" ? Space::light : Space::world;
  const bool standard =
      Unprojector(*light, depth->width, depth->height, 0, space).standard_winding();

  std::vector<Row> rows;
  for (const double e : *bounds) {
    progress.begin("tessellating at " + std::to_string(e));
    const AdaptiveGrid grid = pyramid.tessellate(e, standard);
    Row r;
    r.max_error = e;
    const VolumeCounts counts = adaptive_volume_counts(light->type, grid);
    r.triangles = counts.triangles;
    r.vertices = counts.vertices;
    r.leaves = grid.leaves;
    r.fixup_rounds = grid.fixup_rounds;
    r.balance = grid.balance_seconds;
    r.emit = grid.emit_seconds;
    StageLog m;
    m.begin("measure");
    r.reached = pyramid.measure(grid);
    r.measure = m.end().seconds;
    rows.push_back(r);
    progress.end(thousands(r.triangles) + " triangles");
  }
  const VolumeCounts st = static_volume_counts(light->type, depth->width, depth->height);

  if (o.json) {
    nlohmann::json adaptive = nlohmann::json::array();
    for (const Row& r : rows)
      adaptive.push_back(
          {{"max_error", r.max_error},
           {"triangles", r.triangles},
           {"vertices", r.vertices},
           {"max_error_reached", r.reached},
           {"leaves", r.leaves},
           {"fixup_rounds", r.fixup_rounds},
           {"ratio_to_static", double(r.triangles) / double(st.triangles)},
           {"seconds", {{"balance", r.balance}, {"emit", r.emit}, {"measure", r.measure}}}});
    const nlohmann::json report = {
        {"input", depth_path},
        {"light",
         {{"path", o.light_path},
          {"type", to_string(light->type)},
          {"depth", to_string(light->depth)}}},
        {"width", depth->width},
        {"height", depth->height},
        {"static", {{"triangles", st.triangles}, {"vertices", st.vertices}}},
        {"error_pyramid_seconds", pyramid.seconds()},
        {"adaptive", adaptive}};
    std::printf("%s\n", report.dump(2).c_str());
    return 0;
  }
  if (o.csv) {
    std::printf(
        "mode,max_error,triangles,vertices,max_error_reached,error_pyramid_seconds,balance_seconds,"
        "emit_seconds\n");
    std::printf("static,,%llu,%llu,0,,,\n", static_cast<unsigned long long>(st.triangles),
                static_cast<unsigned long long>(st.vertices));
    for (const Row& r : rows)
      std::printf("adaptive,%.9g,%llu,%llu,%.9g,%.6f,%.6f,%.6f\n", r.max_error,
                  static_cast<unsigned long long>(r.triangles),
                  static_cast<unsigned long long>(r.vertices), r.reached, pyramid.seconds(),
                  r.balance, r.emit);
    return 0;
  }
  std::printf("%s: %dx%d, %s light, %s depth\n", depth_path.c_str(), depth->width, depth->height,
              std::string(to_string(light->type)).c_str(),
              std::string(to_string(light->depth)).c_str());
  std::printf("static grid: %s triangles, %s vertices\n", thousands(st.triangles).c_str(),
              thousands(st.vertices).c_str());
  std::printf("error pyramid: %.3f s (once for all bounds)\n\n", pyramid.seconds());
  std::printf("%12s %14s %14s %9s %14s %10s %10s\n", "max error", "triangles", "vertices",
              "of static", "reached", "balance s", "emit s");
  for (const Row& r : rows)
    std::printf("%12.6g %14s %14s %8.3f%% %14.6g %10.3f %10.3f\n", r.max_error,
                thousands(r.triangles).c_str(), thousands(r.vertices).c_str(),
                100.0 * double(r.triangles) / double(st.triangles), r.reached, r.balance, r.emit);
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
      "'lightvol build --adaptive --max-error E' writes, the largest error actually reached over\n"
      "all texels, and the time of each stage (the error pyramid is built once).");
  cmd->add_option("depth", o->depth_paths,
                  "Depth image: EXR, TIFF, PFM, 16-bit PNG or PGM, HDR, ZFile")
      ->required();
  cmd->add_option("--light", o->light_path, "Light description (LIGHT.json)")->required();
  cmd->add_option("--channel", o->channel, "Channel of a multi-channel image to read (e.g. Z, R)");
  cmd->add_option("--max-error", o->max_errors, "Comma-separated error bounds in world units")
      ->capture_default_str();
  cmd->add_option("--space", o->space, "Frame of the volume (its winding): world or light")
      ->check(CLI::IsMember({"world", "light"}))
      ->capture_default_str();
  cmd->add_flag("--json", o->json, "Print the report as JSON");
  cmd->add_flag("--csv", o->csv, "Print the report as CSV");
  cmd->add_flag("--quiet,-q", o->quiet, "No progress lines");
  cmd->callback([o, run] { *run = [o] { return run_stats(*o); }; });
}

}  // namespace lightvol::cli
