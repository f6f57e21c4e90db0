// lightvol stats: the triangle-count report. The static grid against the adaptive tessellation at
// several error bounds, with the error actually reached and the time of each stage. The counts are
// those `lightvol build --adaptive --max-error E` writes (same library calls).
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <lightvol/depth/depth_image.h>
#include <lightvol/light/light.h>
#include <lightvol/tessellate/adaptive_volume.h>
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

int run_stats(const StatsOptions& o) {
  if (o.json && o.csv) return fail("--json and --csv: choose one");
  Result<std::vector<double>> bounds = parse_bounds(o.max_errors);
  if (!bounds) return fail(bounds.error().message);
  Progress progress(o.quiet || o.json || o.csv);

  progress.begin("reading " + o.light_path);
  Result<Light> light = load_light(o.light_path);
  if (!light) return fail(light.error().message);
  progress.end();
  if (light->type == LightType::omni) return fail(o.light_path + ": omni lights are not supported yet");
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
  const bool standard = Unprojector(*light, depth->width, depth->height, 0, space).standard_winding();

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
      adaptive.push_back({{"max_error", r.max_error},
                          {"triangles", r.triangles},
                          {"vertices", r.vertices},
                          {"max_error_reached", r.reached},
                          {"leaves", r.leaves},
                          {"fixup_rounds", r.fixup_rounds},
                          {"ratio_to_static", double(r.triangles) / double(st.triangles)},
                          {"seconds", {{"balance", r.balance}, {"emit", r.emit}, {"measure", r.measure}}}});
    const nlohmann::json report = {
        {"input", depth_path},
        {"light", {{"path", o.light_path}, {"type", to_string(light->type)}, {"depth", to_string(light->depth)}}},
        {"width", depth->width},
        {"height", depth->height},
        {"static", {{"triangles", st.triangles}, {"vertices", st.vertices}}},
        {"error_pyramid_seconds", pyramid.seconds()},
        {"adaptive", adaptive}};
    std::printf("%s\n", report.dump(2).c_str());
    return 0;
  }
  if (o.csv) {
    std::printf("mode,max_error,triangles,vertices,max_error_reached,error_pyramid_seconds,balance_seconds,emit_seconds\n");
    std::printf("static,,%llu,%llu,0,,,\n", static_cast<unsigned long long>(st.triangles),
                static_cast<unsigned long long>(st.vertices));
    for (const Row& r : rows)
      std::printf("adaptive,%.9g,%llu,%llu,%.9g,%.6f,%.6f,%.6f\n", r.max_error,
                  static_cast<unsigned long long>(r.triangles), static_cast<unsigned long long>(r.vertices),
                  r.reached, pyramid.seconds(), r.balance, r.emit);
    return 0;
  }
  std::printf("%s: %dx%d, %s light, %s depth\n", depth_path.c_str(), depth->width, depth->height,
              std::string(to_string(light->type)).c_str(), std::string(to_string(light->depth)).c_str());
  std::printf("static grid: %s triangles, %s vertices\n", thousands(st.triangles).c_str(),
              thousands(st.vertices).c_str());
  std::printf("error pyramid: %.3f s (once for all bounds)\n\n", pyramid.seconds());
  std::printf("%12s %14s %14s %9s %14s %10s %10s\n", "max error", "triangles", "vertices", "of static",
              "reached", "balance s", "emit s");
  for (const Row& r : rows)
    std::printf("%12.6g %14s %14s %8.3f%% %14.6g %10.3f %10.3f\n", r.max_error, thousands(r.triangles).c_str(),
                thousands(r.vertices).c_str(), 100.0 * double(r.triangles) / double(st.triangles), r.reached,
                r.balance, r.emit);
  return 0;
}

}  // namespace

void add_stats_command(CLI::App& app, Runner* run) {
  auto o = std::make_shared<StatsOptions>();
  CLI::App* cmd = app.add_subcommand(
      "stats", "Triangle-count report: the static grid against adaptive tessellations at several error bounds.");
  cmd->footer(
      "Example:\n  lightvol stats shadow.exr --light light.json --max-error 0.001,0.01,0.1 --csv\n"
      "For each bound E (world units along the texel rays): the triangles and vertices that\n"
      "'lightvol build --adaptive --max-error E' writes, the largest error actually reached over\n"
      "all texels, and the time of each stage (the error pyramid is built once).");
  cmd->add_option("depth", o->depth_paths, "Depth image: EXR, TIFF, PFM, 16-bit PNG, ...")->required();
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
