// lightvol demo: the pipeline on the bundled data/, with a short printed summary.
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <unistd.h>

#include <lightvol/core/mesh.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/export/export.h>
#include <lightvol/light/light.h>
#include <lightvol/volume/static_volume.h>

#include "commands.h"
#include "progress.h"

namespace lightvol::cli {
namespace {
namespace fs = std::filesystem;

struct DemoOptions {
  std::string out_dir = "lightvol-demo";
  std::string data_dir;
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

struct DemoRow {
  std::string name;
  std::string map;
  std::size_t triangles = 0, vertices = 0;
  double volume = 0, seconds = 0;
  std::string file;
};

int run_demo(const DemoOptions& o) {
  const std::string data = find_data_dir(o.data_dir);
  std::error_code ec;
  fs::create_directories(o.out_dir, ec);
  if (!fs::is_directory(o.out_dir)) return fail(o.out_dir + ": cannot create the output directory");

  Progress progress(o.quiet);
  const std::string depth_path = data + "/synthetic_256.exr";
  progress.begin("reading " + depth_path);
  const Result<DepthImage> depth = read_depth_image(depth_path);
  if (!depth) return fail(depth.error().message + " (is --data the bundled data/ folder?)");
  progress.end();

  std::vector<DemoRow> rows;
  for (const char* name : {"spot", "directional"}) {
    const std::string light_path = data + "/" + name + "_light.json";
    const Result<Light> light = load_light(light_path);
    if (!light) return fail(light.error().message);
    progress.begin(std::string("building the static ") + name + " volume");
    const Result<Mesh> mesh = build_static_volume(*light, *depth, {}, depth_path);
    if (!mesh) return fail(mesh.error().message);
    const std::string out = o.out_dir + "/" + name + "_static.ply";
    if (Status s = write_mesh(out, *mesh); !s) return fail(s.error().message);
    progress.end();
    rows.push_back({name, std::to_string(depth->width) + "x" + std::to_string(depth->height),
                    mesh->num_triangles(), mesh->num_vertices(), signed_volume(*mesh),
                    progress.log().stages().back().seconds, out});
  }

  if (!o.quiet) {
    std::printf("%-12s %-9s %12s %10s %12s %8s  %s\n", "light", "map", "triangles", "vertices",
                "volume", "time", "file");
    for (const DemoRow& r : rows)
      std::printf("%-12s %-9s %12s %10s %12.6g %7.2fs  %s\n", r.name.c_str(), r.map.c_str(),
                  thousands(r.triangles).c_str(), thousands(r.vertices).c_str(), r.volume,
                  r.seconds, r.file.c_str());
  }
  return 0;
}

}  // namespace

void add_demo_command(CLI::App& app, Runner* run) {
  auto o = std::make_shared<DemoOptions>();
  CLI::App* cmd = app.add_subcommand("demo", "Run the pipeline on the bundled data and print a summary.");
  cmd->add_option("--out,-o", o->out_dir, "Directory for the meshes the demo writes")->capture_default_str();
  cmd->add_option("--data", o->data_dir, "The bundled data folder (default: found automatically)");
  cmd->add_flag("--quiet,-q", o->quiet, "No progress lines and no summary");
  cmd->callback([o, run] { *run = [o] { return run_demo(*o); }; });
}

}  // namespace lightvol::cli
