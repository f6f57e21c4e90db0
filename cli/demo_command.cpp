// lightvol demo: the whole pipeline on the bundled real scene (data/sponza_crop.ply, the middle of
// the Sponza atrium): shadow map → static and adaptive volumes → check → render, with pictures
// and a short printed summary. The steps are the library's (pipeline/demo.h); here the flags,
// the data folder and the printing.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include <lightvol/pipeline/demo.h>
#ifdef LIGHTVOL_HAS_SHADOWMAP
#include <lightvol/pipeline/gl_demo.h>
#endif

#include "commands.h"
#include "progress.h"

namespace lightvol::cli {
namespace {
namespace fs = std::filesystem;

struct DemoFlags {
  std::string out_dir = "lightvol-demo";
  std::string data_dir;
  int size = 512;
  double max_error = 0.01;
  bool quiet = false;
};

// The bundled data: --data, else share/lightvol/data beside an installed binary, else the
// source tree's data/ this binary was built from.
std::string find_data_dir(const std::string& given) {
  if (!given.empty()) return given;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path installed = exe.parent_path().parent_path() / "share" / "lightvol" / "data";
    if (fs::is_directory(installed, ec)) return installed.string();
  }
  return LIGHTVOL_DATA_DIR;
}

int run_demo_command(const DemoFlags& f) {
  DemoOptions o;
  o.data_dir = find_data_dir(f.data_dir);
  o.out_dir = f.out_dir;
  o.size = f.size;
  o.max_error = f.max_error;
#ifdef LIGHTVOL_HAS_SHADOWMAP
  o.gpu = gl_demo_steps();
#endif
  Progress progress(f.quiet);
  const Result<DemoReport> report = run_demo(o, progress.log());
  if (!report) return fail(report.error());
  if (f.quiet) return 0;
  std::printf("%s", demo_table(*report).c_str());
  std::printf("outputs in %s/ (scene: Sponza atrium by Marko Dabrovic, the middle of the atrium)\n",
              o.out_dir.c_str());
  const fs::path serve = fs::path(o.data_dir).parent_path() / "web" / "serve.mjs";
  if (fs::exists(serve))
    std::printf(
        "view it in a browser: node %s %s\n  then open "
        "http://127.0.0.1:8000/web/"
        "index.html?volume=/data/volume_static.glb&camera=/data/camera.json&medium=/data/"
        "medium.json&scene=/data/scene.glb\n"
        "  or the live page (drag the light; a ball moves through it): "
        "http://127.0.0.1:8000/web/"
        "live.html?scene=/data/scene.glb&light=/data/light.json&medium=/data/"
        "medium.json&camera=/data/camera.json&animate=1\n",
        serve.string().c_str(), o.out_dir.c_str());
  return 0;
}

}  // namespace

void add_demo_command(CLI::App& app, Runner* run) {
  auto o = std::make_shared<DemoFlags>();
  CLI::App* cmd = app.add_subcommand(
      "demo", "Run the whole pipeline on the bundled scene (part of Sponza) and print a summary.");
  cmd->footer(
      "Renders the bundled scene's spot shadow map and camera depth (OpenGL, headless; CPU ray\n"
      "casting without it), builds the static and the adaptive light volume, checks both, renders\n"
      "the airlight, and writes meshes, depth images and PNGs to --out.");
  cmd->add_option("--out,-o", o->out_dir, "Directory for everything the demo writes")
      ->capture_default_str();
  cmd->add_option("--size", o->size,
                  "Shadow-map size (sizes below 512 also shrink the camera image)")
      ->check(decimal_integer())
      ->check(CLI::Range(8, 4096))
      ->capture_default_str();
  cmd->add_option("--max-error", o->max_error, "Adaptive volume's error bound, world units")
      ->check(decimal_number(0))
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--data", o->data_dir, "The bundled data folder (default: found automatically)");
  cmd->add_flag("--quiet,-q", o->quiet, "No progress lines and no summary");
  cmd->callback([o, run] { *run = [o] { return run_demo_command(*o); }; });
}

}  // namespace lightvol::cli
