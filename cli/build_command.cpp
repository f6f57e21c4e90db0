// lightvol build: depth image(s) + light description → closed light volume on disk. One library
// call (pipeline/build_file.h build_volume_file); here the flags, the warnings and the summary.
#include <cstdio>
#include <memory>
#include <string>

#include <lightvol/core/path.h>
#include <lightvol/core/stages.h>
#include <lightvol/pipeline/build_file.h>

#include "build_flags.h"
#include "commands.h"
#include "progress.h"

namespace lightvol::cli {
namespace {

int run_build(const BuildCommandOptions& o) {
  Result<BuildFileOptions> options = build_file_options(o);
  if (!options) return fail(options.error());
  Progress progress(o.quiet);
  const BuildFileResult r = build_volume_file(*options, progress.log());
  // Warnings go to stderr (unless --quiet) and into the report.
  if (!o.quiet)
    for (const std::string& w : r.warnings)
      std::fprintf(stderr, "lightvol: warning: %s\n", printable(w).c_str());
  if (!r.status) return fail(r.status.error());
  if (o.json) {
    std::printf("%s\n", r.report.c_str());
  } else if (!o.quiet) {
    // After a report on standard output (--report -), the summary goes to stderr: stdout stays
    // one JSON document.
    std::FILE* summary = named_descriptor(o.report_path) == 1 ? stderr : stdout;
    std::fprintf(summary, "wrote %s: %s triangles, %s vertices, volume %.6g, %.2f s, peak %s\n",
                 o.out_path.c_str(), thousands(r.triangles).c_str(), thousands(r.vertices).c_str(),
                 r.volume, progress.log().total_seconds(),
                 human_bytes(peak_memory_bytes()).c_str());
  }
  return 0;
}

}  // namespace

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
