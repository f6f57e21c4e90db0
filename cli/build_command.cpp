// lightvol build: depth image(s) + light description → closed light volume on disk.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <lightvol/airlight/airlight.h>
#include <lightvol/check/check.h>
#include <lightvol/core/atomic_file.h>
#include <lightvol/core/mesh.h>
#include <lightvol/core/path.h>
#include <lightvol/core/text_file.h>
#include <lightvol/depth/cube_faces.h>
#include <lightvol/depth/shadow_maps.h>
#include <lightvol/export/export.h>
#include <lightvol/light/light.h>
#include <lightvol/volume/build_volume.h>
#include <lightvol/volume/static_volume.h>

#include "build_job.h"
#include "commands.h"
#include "progress.h"

namespace lightvol::cli {
namespace {

// Flag combinations that make no sense; "" when the flags agree.
std::string conflicting_flags(const BuildCommandOptions& o, MeshFormat format) {
  if (o.draco && format != MeshFormat::glb) return "--draco: applies to .glb output only";
  if (!o.medium_path.empty() && format != MeshFormat::glb)
    return "--medium: applies to .glb output only (the file records it beside the light)";
  if (o.ascii && format != MeshFormat::ply && format != MeshFormat::stl)
    return "--ascii: applies to .ply and .stl output only";
  if (o.json && !o.report_path.empty() && named_descriptor(o.report_path) == 1)
    return "--report " + o.report_path + ": --json prints the report on standard output already";
  if (o.refine == "error" && o.adaptive && o.max_error < 0)
    return "--adaptive: needs --max-error E (world units along the texel rays)";
  if (o.refine == "error" && !o.adaptive && o.max_error >= 0)
    return "--max-error: applies with --adaptive only";
  if (o.refine == "laplacian" && o.threshold < 0) return "--refine laplacian: needs --threshold T";
  if (o.refine == "laplacian" && o.max_error >= 0)
    return "--max-error: does not apply to --refine laplacian (use --threshold)";
  if (o.refine == "error" && o.threshold >= 0)
    return "--threshold: applies with --refine laplacian only";
  if (!o.tessellation.empty() && !o.adaptive && o.refine != "laplacian")
    return "--tessellation: applies with --adaptive only";
  if (o.refine == "laplacian" && o.tessellation == "collapse")
    return "--tessellation collapse: needs a bound (--refine error); laplacian uses quadtree";
  return "";
}

BuildVolumeOptions volume_options(const BuildCommandOptions& o) {
  BuildVolumeOptions v;
  v.space = o.space == "light" ? Space::light : Space::world;
  const bool adaptive = o.adaptive || o.refine == "laplacian";
  v.grid = adaptive ? VolumeGrid::adaptive : VolumeGrid::static_grid;
  v.adaptive.refinement = o.refine == "laplacian" ? Refinement::laplacian : Refinement::max_error;
  v.adaptive.max_error = o.max_error;
  v.adaptive.threshold = o.threshold;
  v.adaptive.tessellation =
      o.tessellation == "quadtree" ? Tessellation::quadtree : Tessellation::collapse;
  v.adaptive.measure = o.json || !o.report_path.empty();  // the reached error is for reports
  v.light_source = o.light_path;
  return v;
}

// The --medium file as a GLB records it: checked by load_medium, without its formatting.
// `text` is the file's bytes when the caller has read them; else the file is read here, once (a
// pipe has no second reading).
Result<std::string> medium_json(const std::string& path, const std::string* text) {
  Result<std::string> read =
      text ? Result<std::string>(*text) : read_text_file(path, "medium description");
  if (!read) return read.error();
  if (Result<Medium> medium = parse_medium(*read, path); !medium) return medium.error();
  const nlohmann::json medium = nlohmann::json::parse(*read, nullptr, false);
  if (medium.is_discarded()) return Error{path + ": not JSON"};  // parse_medium parsed it
  return medium.dump();
}

nlohmann::json stage_json(const StageLog& log) {
  nlohmann::json stages = nlohmann::json::array();
  for (const StageRecord& s : log.stages())
    stages.push_back(
        {{"name", s.name}, {"seconds", s.seconds}, {"peak_memory_bytes", s.peak_memory_bytes}});
  return stages;
}

// What the report says of the volume written (a streamed volume is not held: its stream tallies
// these).
struct VolumeSummary {
  std::uint64_t vertices = 0, triangles = 0;
  Bounds bounds;
  double volume = 0;
};

VolumeSummary summary_of(const Mesh& mesh) {
  return {mesh.num_vertices(), mesh.num_triangles(), bounding_box(mesh), signed_volume(mesh)};
}

// The memory a build in these modes takes (the budget's estimate, checked as the map is read).
BuildMemory memory_mode(const BuildCommandOptions& o, bool adaptive, bool streamed) {
  if (adaptive) return BuildMemory::adaptive;
  if (streamed) return BuildMemory::static_streamed;
  return o.no_check ? BuildMemory::static_unchecked : BuildMemory::static_checked;
}

// The --report / --json report of a finished build.
nlohmann::json build_report(const BuildCommandOptions& o, const Light& light,
                            const ShadowMaps& maps, const VolumeSummary& mesh,
                            const AdaptiveReport* adaptive, const StageLog& log,
                            const std::vector<std::string>& warnings, const nlohmann::json& extra) {
  const Bounds& box = mesh.bounds;
  nlohmann::json report = {
      {"inputs", o.depth_paths},
      {"light",
       {{"path", o.light_path},
        {"type", to_string(light.type)},
        {"depth", to_string(light.depth)}}},
      {"output", o.out_path},
      {"space", o.space},
      {"width", maps.width()},
      {"height", maps.height()},
      {"mode", adaptive ? "adaptive" : "static"},
      {"vertices", mesh.vertices},
      {"triangles", mesh.triangles},
      {"bounds", {{"min", box.min}, {"max", box.max}}},
      {"volume", mesh.volume},
      {"stages", stage_json(log)},
      {"total_seconds", log.total_seconds()},
      {"peak_memory_bytes", peak_memory_bytes()},
      {"warnings", warnings},
  };
  for (const auto& [key, value] : extra.items()) report[key] = value;
  if (!adaptive) return report;
  const AdaptiveReport& a = *adaptive;
  const bool laplacian = o.refine == "laplacian";
  report["adaptive"] = {
      {"refine", o.refine},
      {"tessellation", !laplacian && o.tessellation != "quadtree" ? "collapse" : "quadtree"},
      {"max_error", laplacian ? nlohmann::json(nullptr) : nlohmann::json(o.max_error)},
      {"threshold", laplacian ? nlohmann::json(o.threshold) : nlohmann::json(nullptr)},
      {"max_error_reached", a.max_error_reached},
      {"grid_triangles", a.grid_triangles},
      {"quadtree_triangles", a.quadtree_triangles},
      {"collapses", a.collapses},
      {"min_angle_degrees", a.min_angle_degrees},
      {"min_area_texels", a.min_area},
      {"leaves", a.leaves},
      {"fixup_rounds", a.fixup_rounds},
      {"seconds",
       {{"error_pyramid", a.pyramid_seconds},
        {"balance", a.balance_seconds},
        {"emit", a.emit_seconds},
        {"collapse", a.collapse_seconds},
        {"measure", a.measure_seconds},
        {"assemble", a.assemble_seconds}}}};
  return report;
}

// Every file a build run writes is written here, and only here: the volume (by `write_volume`,
// under the progress line `what`), then the --report JSON, made by `report_of` once the volume is
// written (it records that step's time). Returns the report, for --json.
Result<nlohmann::json> write_outputs(const BuildCommandOptions& o, const std::string& what,
                                     const std::function<Status()>& write_volume,
                                     Progress& progress,
                                     const std::function<nlohmann::json()>& report_of,
                                     const BuildJobHooks& hooks) {
  // The volume and the report are committed together once both are written, or neither is.
  OutputTransaction outputs;
  progress.begin(what);
  if (Status s = write_volume(); !s) return s.error();
  progress.end();
  nlohmann::json report = report_of();
  if (hooks.volume_written) {
    const std::string file = outputs.staged_file(o.out_path);
    if (file.empty()) return Error{o.out_path + ": the volume was not written to a file"};
    Result<nlohmann::json> keys = hooks.volume_written(file);
    if (!keys) return keys.error();
    for (const auto& [key, value] : keys->items()) report[key] = value;
  }
  if (!o.report_path.empty()) {
    if (Status s = write_bytes_atomically(o.report_path, json_text(report, 2) + "\n"); !s)
      return s.error();
  }
  if (Status s = outputs.commit(); !s) return s.error();
  return report;
}

// The seconds of the step `progress` just ended.
double last_step_seconds(const Progress& progress) {
  return progress.log().stages().back().seconds;
}

// --no-check, static, PLY: the volume built row by row straight into the file, never held whole
// (its memory does not grow with the mesh); still refused, with nothing written, when float32
// cannot hold it. Fills `r` as run_build_job does.
void write_streamed(const BuildCommandOptions& o, const Light& light, const ShadowMaps& maps,
                    Space space, Progress& progress, const BuildJobHooks& hooks,
                    BuildJobResult& r) {
  StaticVolumeStream stream(light, maps.image, VolumeOptions{space}, maps.source, o.light_path);
  ExportOptions eo;
  eo.ascii = o.ascii;
  VolumeSummary summary;
  Result<nlohmann::json> report = write_outputs(
      o, "building the static volume into " + o.out_path,
      [&]() -> Status {
        if (Status s = write_mesh_stream(o.out_path, stream, eo); !s) return s;
        summary = {stream.num_vertices(), stream.num_triangles(), stream.bounds(), stream.volume()};
        return {};
      },
      progress,
      [&] {
        r.write_seconds = last_step_seconds(progress);
        return build_report(o, light, maps, summary, nullptr, progress.log(), r.warnings,
                            hooks.extra_report);
      },
      hooks);
  if (!report) {
    r.exit_code = exit_code(report.error().kind);
    r.kind = report.error().kind;
    r.error = report.error().message;
    return;
  }
  r.vertices = summary.vertices;
  r.triangles = summary.triangles;
  r.report = std::move(*report);
}

int run_build(const BuildCommandOptions& o) {
  Progress progress(o.quiet);
  const BuildJobResult r = run_build_job(o, progress);
  // Warnings go to stderr (unless --quiet) and into the report.
  if (!o.quiet)
    for (const std::string& w : r.warnings)
      std::fprintf(stderr, "lightvol: warning: %s\n", printable(w).c_str());
  if (r.exit_code != 0) return fail(Error{r.error, r.kind});
  if (o.json) {
    std::printf("%s\n", json_text(r.report, 2).c_str());
  } else if (!o.quiet) {
    // After a report on standard output (--report -), the summary goes to stderr: stdout stays
    // one JSON document.
    std::FILE* summary = named_descriptor(o.report_path) == 1 ? stderr : stdout;
    std::fprintf(summary, "wrote %s: %s triangles, %s vertices, volume %.6g, %.2f s, peak %s\n",
                 o.out_path.c_str(), thousands(r.triangles).c_str(), thousands(r.vertices).c_str(),
                 r.report["volume"].get<double>(), progress.log().total_seconds(),
                 human_bytes(peak_memory_bytes()).c_str());
  }
  return 0;
}

}  // namespace

void add_build_options(CLI::App& cmd, BuildCommandOptions& o) {
  cmd.add_option("depth", o.depth_paths,
                 "Depth image: EXR, TIFF, PFM, 16-bit PNG or PGM, HDR, ZFile (omni: six faces, one "
                 "{face} path or one W x 6W strip)")
      ->required();
  cmd.add_option("--light", o.light_path, "Light description (LIGHT.json)")->required();
  cmd.add_option("--out,-o", o.out_path, "Output mesh; the extension picks the format")->required();
  cmd.add_option("--channel", o.channel, "Channel of a multi-channel image to read (e.g. Z, R)");
  cmd.add_option("--space", o.space, "Frame of the output: world or light (the light's eye space)")
      ->check(CLI::IsMember({"world", "light"}))
      ->capture_default_str();
  cmd.add_flag("--ascii", o.ascii, "Write ASCII PLY or STL instead of binary");
  cmd.add_flag("--draco", o.draco, "Compress .glb output with KHR_draco_mesh_compression");
  cmd.add_option("--draco-bits", o.draco_bits, "Position quantization bits for .drc and --draco")
      ->check(decimal_integer())
      ->check(CLI::Range(1, 30))
      ->capture_default_str();
  cmd.add_option("--medium", o.medium_path,
                 "Medium JSON to record in a .glb beside the light (its intensity becomes the glTF "
                 "light's)");
  cmd.add_option(
      "--report", o.report_path,
      "Write a JSON report: counts, bounds, volume, time and peak memory per stage (- for "
      "standard output)");
  cmd.add_flag("--json", o.json, "Print the report as JSON on stdout");
  cmd.add_flag(
      "--adaptive", o.adaptive,
      "Adaptive tessellation: every texel lies within --max-error world units of the surface (no "
      "T-junctions; see --tessellation)");
  cmd.add_option("--max-error", o.max_error,
                 "Error bound of --adaptive, in world units along each texel ray")
      ->check(decimal_number(0));
  cmd.add_option(
         "--refine", o.refine,
         "Refinement criterion: error (the bound, default) or laplacian (the paper's edge map; "
         "implies --adaptive)")
      ->check(CLI::IsMember({"error", "laplacian"}));
  cmd.add_option("--threshold", o.threshold,
                 "--refine laplacian: split cells whose |Laplacian of window depth| exceeds this")
      ->check(decimal_number(0));
  cmd.add_option("--tessellation", o.tessellation,
                 "--adaptive: collapse (default: the quadtree coarsened by collapses verified at "
                 "every texel, far fewer triangles) or quadtree (the paper's restricted quadtree; "
                 "the only one for --refine laplacian)")
      ->check(CLI::IsMember({"collapse", "quadtree"}));
  cmd.add_flag(
      "--no-check", o.no_check,
      "Write without the linear-time checks (which otherwise refuse a failing volume, exit 1)");
  cmd.add_flag("--quiet,-q", o.quiet, "No progress lines and no summary");
}

nlohmann::json output_options_json(const BuildCommandOptions& o) {
  return {{"format", std::filesystem::path(o.out_path).extension().string()},
          {"channel", o.channel},
          {"space", o.space},
          {"ascii", o.ascii},
          {"draco", o.draco},
          {"draco_bits", o.draco_bits},
          {"adaptive", o.adaptive},
          {"max_error", o.max_error},
          {"refine", o.refine},
          {"threshold", o.threshold},
          {"tessellation", o.tessellation},
          {"no_check", o.no_check},
          {"medium", !o.medium_path.empty()}};
}

BuildJobResult run_build_job(const BuildCommandOptions& o, Progress& progress,
                             const BuildJobHooks& hooks) {
  BuildJobResult r;
  auto failed = [&r](Error error) {
    r.exit_code = exit_code(error.kind);
    r.kind = error.kind;
    r.error = std::move(error.message);
    return r;
  };
  // A NUL would end a path early, a line break split a message: no path may hold either.
  std::vector<std::pair<std::string, std::string>> paths = {{"--light", o.light_path},
                                                            {"--out", o.out_path},
                                                            {"--report", o.report_path},
                                                            {"--medium", o.medium_path}};
  for (const std::string& p : o.depth_paths) paths.emplace_back("depth input", p);
  for (const auto& [flag, path] : paths)
    if (const std::string where = control_character_in(path); !where.empty())
      return failed(Error{flag + ": " + where + " in the path; paths may not hold one"});
  // No output may replace an input (compared by identity: the same inode, or the same new path).
  std::vector<std::pair<std::string, std::string>> inputs = {{"--light", o.light_path},
                                                             {"--medium", o.medium_path}};
  for (const std::string& p : o.depth_paths) {
    if (p.find("{face}") == std::string::npos) inputs.emplace_back("depth input", p);
    for (int face = 0; face < kOmniFaces && p.find("{face}") != std::string::npos; ++face)
      inputs.emplace_back("depth input", expand_face_pattern(p, face));
  }
  for (const auto& [out_flag, out] :
       {std::pair<std::string, std::string>{"--out", o.out_path}, {"--report", o.report_path}}) {
    if (out.empty()) continue;
    const std::string identity = file_identity(out);
    for (const auto& [in_flag, in] : inputs)
      if (!in.empty() && file_identity(in) == identity)
        return failed(Error{out_flag + " " + out + ": is also the " + in_flag + " " + in +
                            "; an output may not replace an input"});
  }
  Result<MeshFormat> format = mesh_format_from_path(o.out_path);
  if (!format) return failed(format.error());
  if (const std::string conflict = conflicting_flags(o, *format); !conflict.empty())
    return failed(Error{conflict});
  const BuildVolumeOptions options = volume_options(o);
  const bool adaptive = options.grid == VolumeGrid::adaptive;

  progress.begin("reading " + o.light_path);
  Result<Light> light =
      hooks.light_text ? parse_light(*hooks.light_text, o.light_path) : load_light(o.light_path);
  if (!light) return failed(light.error());
  progress.end();
  r.read_seconds += last_step_seconds(progress);
  Result<std::string> medium = o.medium_path.empty()
                                   ? Result<std::string>(std::string())
                                   : medium_json(o.medium_path, hooks.medium_text);
  if (!medium) return failed(medium.error());

  const bool omni = light->type == LightType::omni;
  // A static volume written unchecked to PLY is streamed: built row by row into the file.
  const bool streamed = !adaptive && !omni && o.no_check && *format == MeshFormat::ply;
  progress.begin(omni ? "reading omni faces" : "reading " + o.depth_paths.front());
  DepthReadOptions read_options;
  read_options.channel = o.channel;
  read_options.memory = memory_mode(o, adaptive, streamed);
  Result<ShadowMaps> maps = read_shadow_maps(*light, o.depth_paths, read_options);
  if (!maps) return failed(maps.error());
  progress.end(size_text(maps->width(), maps->height()) + (omni ? " x 6" : ""));
  r.read_seconds += last_step_seconds(progress);

  // Warnings go into the report (and the caller says them).
  if (const std::string note = omni ? "" : aspect_mismatch(*light, maps->width(), maps->height());
      !note.empty())
    r.warnings.push_back(o.depth_paths.front() + ": " + note);

  if (hooks.after_read)
    if (Status s = hooks.after_read(); !s) return failed(s.error());
  if (hooks.before_build) {
    const auto waited_from = std::chrono::steady_clock::now();
    hooks.before_build(*maps, read_options.memory);
    r.wait_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - waited_from).count();
  }

  if (streamed) {
    write_streamed(o, *light, *maps, options.space, progress, hooks, r);
    return r;
  }

  progress.begin(std::string("building ") + (adaptive ? "adaptive " : "static ") +
                 (omni ? "omni " : "") + "volume");
  AdaptiveReport adaptive_report;
  // A valid light whose volume float32 cannot hold is bad input (exit 2), not an invalid volume.
  Result<Mesh> mesh = build_volume(*light, *maps, options, &adaptive_report);
  if (!mesh) return failed(mesh.error());
  progress.end(thousands(mesh->num_triangles()) + " triangles");
  r.build_seconds = last_step_seconds(progress);

  const Light frame_light = light_in_space(*light, options.space);
  if (!o.no_check) {
    // The linear-time checks with the light: refuse to write a volume that is not sound.
    progress.begin("checking");
    const CheckReport check = check_volume_linear(*mesh, &frame_light);
    if (!check.valid())
      return failed(Error{o.out_path + ": the built volume fails its checks, nothing written: " +
                              check.first_failure(),
                          ErrorKind::unsound});
    progress.end("valid");
    r.check_seconds = last_step_seconds(progress);
  }

  ExportOptions eo;
  eo.ascii = o.ascii;
  eo.draco = o.draco;
  eo.draco_bits = o.draco_bits;
  if (!o.no_check) eo.light = &frame_light;  // a lossy encoding must stay sound seen from the light
  eo.glb.light = &frame_light;               // a GLB carries its light, in the volume's frame
  eo.glb.medium_json = *medium;
  const VolumeSummary summary = summary_of(*mesh);
  Result<nlohmann::json> report = write_outputs(
      o, "writing " + o.out_path, [&] { return write_mesh(o.out_path, *mesh, eo); }, progress,
      [&] {
        r.write_seconds = last_step_seconds(progress);
        return build_report(o, *light, *maps, summary, adaptive ? &adaptive_report : nullptr,
                            progress.log(), r.warnings, hooks.extra_report);
      },
      hooks);
  if (!report) return failed(report.error());
  r.vertices = mesh->num_vertices();
  r.triangles = mesh->num_triangles();
  r.report = std::move(*report);
  return r;
}

void add_build_command(CLI::App& app, Runner* run) {
  auto o = std::make_shared<BuildCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "build", "Build the closed light volume of a shadow map and write it as a mesh.");
  cmd->footer(
      "Example:\n  lightvol build shadow.exr --light light.json --out volume.ply\n"
      "  lightvol build 'room_{face}.exr' --light omni.json --out volume.ply\n"
      "The volume has one vertex per texel, at the texel centre's ray and depth, closed to the\n"
      "light (spot: a fan to its position; directional: walls and a cap on the near plane; omni:\n"
      "six faces joined by seams along the cube's edges and a triangle at each corner).\n"
      "An omni light takes six images (+X -X +Y -Y +Z -Z), one path with {face} (px nx py ny pz "
      "nz)\n"
      "or one W x 6W strip with the faces top to bottom.\n"
      "Formats by extension: .ply .obj .off .stl .drc .glb. Exit 2 on bad input, with no file "
      "written.");
  add_build_options(*cmd, *o);
  cmd->callback([o, run] { *run = [o] { return run_build(*o); }; });
}

}  // namespace lightvol::cli
