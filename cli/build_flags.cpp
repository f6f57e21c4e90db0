// The `lightvol build` command line (build_flags.h): its flags, their conflicts, the library's
// options they make.
#include "build_flags.h"

#include <filesystem>
#include <string>

#include <lightvol/core/path.h>
#include <lightvol/io/mesh_format.h>

#include "commands.h"

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

Result<BuildFileOptions> build_file_options(const BuildCommandOptions& o) {
  // An output of no format is the library's to refuse (after the paths' checks).
  if (Result<MeshFormat> format = mesh_format_from_path(o.out_path); format)
    if (const std::string conflict = conflicting_flags(o, *format); !conflict.empty())
      return Error{conflict};
  BuildFileOptions f;
  f.depth_paths = o.depth_paths;
  f.light_path = o.light_path;
  f.out_path = o.out_path;
  f.report_path = o.report_path;
  f.make_report = o.json;
  f.medium_path = o.medium_path;
  f.channel = o.channel;
  BuildVolumeOptions& v = f.volume;
  v.space = o.space == "light" ? Space::light : Space::world;
  const bool adaptive = o.adaptive || o.refine == "laplacian";
  v.grid = adaptive ? VolumeGrid::adaptive : VolumeGrid::static_grid;
  v.adaptive.refinement = o.refine == "laplacian" ? Refinement::laplacian : Refinement::max_error;
  v.adaptive.max_error = o.max_error;
  v.adaptive.threshold = o.threshold;
  v.adaptive.tessellation =
      o.tessellation == "quadtree" ? Tessellation::quadtree : Tessellation::collapse;
  f.check = !o.no_check;
  f.ascii = o.ascii;
  f.draco = o.draco;
  f.draco_bits = o.draco_bits;
  return f;
}

}  // namespace lightvol::cli
