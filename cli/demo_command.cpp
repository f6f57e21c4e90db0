// lightvol demo: the whole pipeline on the bundled real scene (data/sponza_crop.ply, the middle of
// the Sponza atrium): shadow map → static and adaptive volumes → check → render, with pictures
// and a short printed summary.
#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <lightvol/airlight/airlight.h>
#include <lightvol/core/atomic_file.h>
#include <lightvol/core/mesh.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/depth/shadow_maps.h>
#include <lightvol/export/export.h>
#include <lightvol/light/camera.h>
#include <lightvol/light/light.h>
#include <lightvol/pipeline/build_file.h>
#include <lightvol/render/image_io.h>
#include <lightvol/render/scene.h>
#include <lightvol/render/surfaces.h>
#include <lightvol/scene/depth_passes.h>
#include <lightvol/scene/scene.h>
#ifdef LIGHTVOL_HAS_SHADOWMAP
#include <lightvol/render/fog_picture.h>
#include <lightvol/render/gl_marchers.h>
#include <lightvol/render/gl_volume.h>
#include <lightvol/scene/shadowmap.h>
#endif

#include "commands.h"
#include "progress.h"

namespace lightvol::cli {
namespace {
namespace fs = std::filesystem;

struct DemoOptions {
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

// The printed summary: one row per step, with the step's time from the progress log.
class Summary {
 public:
  explicit Summary(Progress& progress) : progress_(progress) {}
  // Ends the current progress step and records it.
  void add(const std::string& step, const std::string& file, const std::string& count,
           const std::string& result) {
    progress_.end();
    rows_.push_back({step, file, count, result, progress_.log().stages().back().seconds});
  }
  struct Row {
    std::string step, file, count, result;
    double seconds = 0;
  };
  // A row for steps the library timed.
  void row(Row r) { rows_.push_back(std::move(r)); }
  // A row for a step that did not run.
  void skipped(const std::string& step, const std::string& why) {
    rows_.push_back({step, "", "", "skipped: " + why, 0});
  }
  void print(const std::string& out_dir) const {
    std::printf("%-26s %-22s %-18s %8s  %s\n", "step", "output", "size", "time", "result");
    for (const Row& r : rows_)
      std::printf("%-26s %-22s %-18s %7.2fs  %s\n", r.step.c_str(), r.file.c_str(), r.count.c_str(),
                  r.seconds, r.result.c_str());
    std::printf(
        "outputs in %s/ (scene: Sponza atrium by Marko Dabrovic, the middle of the atrium)\n",
        out_dir.c_str());
  }

 private:
  Progress& progress_;
  std::vector<Row> rows_;
};

// The bundled scene, its spot light, camera and medium.
struct DemoScene {
  Mesh mesh;
  Light light;
  Camera camera;
  Medium medium;
  Medium fog;  // the medium of varying density beside it (demo_fog.png)
};

Result<DemoScene> load_demo_scene(const std::string& data, int size) {
  DemoScene s;
  Result<Mesh> mesh = load_scene(data + "/sponza_crop.ply");
  if (!mesh) return Error{mesh.error().message + " (is --data the bundled data/ folder?)"};
  s.mesh = std::move(*mesh);
  Result<Light> light = load_light(data + "/sponza_demo_spot.json");
  if (!light) return light.error();
  s.light = *light;
  Result<Camera> camera = load_camera(data + "/sponza_camera.json");
  if (!camera) return camera.error();
  s.camera = *camera;
  Result<Medium> medium = load_medium(data + "/sponza_demo_medium.json");
  if (!medium) return medium.error();
  s.medium = *medium;
  Result<Medium> fog = load_medium(data + "/sponza_demo_fog.json");
  if (!fog) return fog.error();
  s.fog = *fog;
  // Smaller shadow maps (tests) get a proportionally smaller camera image.
  if (size < 512) {
    s.camera.width = std::max(16, s.camera.width * size / 512);
    s.camera.height = std::max(16, s.camera.height * size / 512);
  }
  return s;
}

// Depth passes on the GPU when an OpenGL context can be made (it stays current for the airlight
// renders), else by CPU ray casting; `why_not_gl` says why not.
std::unique_ptr<DepthPasses> open_depth_passes(const Mesh& scene, const std::string& source,
                                               std::string* why_not_gl) {
#ifdef LIGHTVOL_HAS_SHADOWMAP
  Result<std::unique_ptr<DepthPasses>> gl = gl_depth_passes(scene, source);
  if (gl) return std::move(*gl);
  *why_not_gl = gl.error().message;
#else
  (void)source;
  *why_not_gl = "built without OpenGL (LIGHTVOL_WITH_GL=OFF)";
#endif
  return cpu_depth_passes(scene);
}

// One depth pass of `view`, written as NAME.exr (its depth encoding) and NAME.png (a preview).
Result<RenderedPasses> depth_pass(DepthPasses& passes, const Light& view, MapSize size,
                                  const std::string& name) {
  Result<RenderedPasses> pass = render_passes(passes, view, size);
  if (!pass) return pass.error();
  if (Status s = write_depth_image(name + ".exr", pass->maps.image); !s) return s.error();
  if (Status s = write_depth_image(name + ".png",
                                   depth_preview(view, size.width, size.height, pass->window));
      !s)
    return s.error();
  return pass;
}

struct Volume {
  std::string name;
  Mesh mesh;
};

// The static and the adaptive volume of the shadow map, each checked from the light and written
// as volume_NAME.ply (build_volume_file: nothing written when it fails its checks). The rows of
// their checks go to `checks`, for the table after the viewer's inputs.
Result<std::vector<Volume>> build_volumes(const Light& light, const ShadowMaps& shadow,
                                          const std::string& light_path, double max_error,
                                          const std::string& out_dir, Progress& progress,
                                          Summary& summary, std::vector<Summary::Row>* checks) {
  std::vector<Volume> volumes;
  for (const bool adaptive : {false, true}) {
    const std::string name = adaptive ? "adaptive" : "static";
    const std::string file = "volume_" + name + ".ply";
    BuildFileOptions options;
    options.light = &light;
    options.maps = &shadow;
    options.light_path = light_path;
    options.depth_paths = {out_dir + "/shadow_map.exr"};
    options.out_path = out_dir + "/" + file;
    options.volume.grid = adaptive ? VolumeGrid::adaptive : VolumeGrid::static_grid;
    options.volume.adaptive.max_error = max_error;
    options.keep_mesh = true;
    BuildFileResult built = build_volume_file(options, progress.log());
    if (!built.status) return built.status.error();
    char error_text[64];
    std::snprintf(error_text, sizeof error_text, "max error %g", max_error);
    summary.row({name + " volume", file, thousands(built.triangles) + " tris",
                 adaptive ? error_text : "", built.seconds.build + built.seconds.write});
    checks->push_back({"check " + name, "", "",
                       "valid (" + std::string(to_string(built.check.proof)) + ")",
                       built.seconds.check});
    volumes.push_back({name, std::move(built.mesh)});
  }
  return volumes;
}

// What the web viewer (web/) needs beside the demo's other outputs: the volumes as GLBs carrying
// their light and the medium, the scene as a GLB, the camera (at the demo's image size) and the
// medium; the live page (web/live.html) also the light (light.json, the demo's spot).
Status write_viewer_inputs(const std::string& data, const std::string& dir, const Mesh& scene,
                           const Light& light, const Camera& camera,
                           const std::vector<Volume>& volumes) {
  const auto slurp = [](const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  const std::string medium_text = slurp(data + "/sponza_demo_medium.json");
  nlohmann::json camera_json =
      nlohmann::json::parse(slurp(data + "/sponza_camera.json"), nullptr, false);
  if (camera_json.is_discarded()) return Error{data + "/sponza_camera.json: not JSON"};
  camera_json["width"] = camera.width;
  camera_json["height"] = camera.height;
  Result<std::string> medium = medium_record_json(medium_text, data + "/sponza_demo_medium.json");
  if (!medium) return medium.error();
  ExportOptions options;
  options.glb.light = &light;
  options.glb.medium_json = std::move(*medium);
  for (const Volume& v : volumes)
    if (Status s = write_mesh(dir + "/volume_" + v.name + ".glb", v.mesh, options); !s) return s;
  if (Status s = write_mesh(dir + "/scene.glb", scene); !s) return s;
  if (Status s = write_bytes_atomically(dir + "/camera.json", json_text(camera_json, 2) + "\n"); !s)
    return s;
  if (Status s =
          write_bytes_atomically(dir + "/light.json", slurp(data + "/sponza_demo_spot.json"));
      !s)
    return s;
  return write_bytes_atomically(dir + "/medium.json", medium_text);
}

#ifdef LIGHTVOL_HAS_SHADOWMAP
// demo.png's colours: a warm spot light (about 3,000 K) and a cool ambient light (the sky); its
// ambient radiance; and the exposure, the tone-mapped value (x/(1+x) of it) of the picture's
// 99.5th percentile.
constexpr std::array<double, 3> kLightColour = {1.0, 0.72, 0.42};
constexpr std::array<double, 3> kAmbientColour = {0.5, 0.62, 0.9};
constexpr double kDemoAmbient = 0.0002;
constexpr double kDemoExposure = 1.2;

// The airlight of each volume and of ray marching, and the picture: lit surfaces plus the static
// volume's airlight. Every PNG uses the static volume's exposure, so that they compare by eye.
Status render_pictures(const RenderScene& scene, const Medium& fog,
                       const std::vector<Volume>& volumes, const ShadowMaps& shadow,
                       const RenderedPasses& shadow_pass, const std::string& out_dir,
                       Progress& progress, Summary& summary) {
  const auto out = [&](const std::string& name) { return out_dir + "/" + name; };
  const std::string size = size_text(scene.camera.width, scene.camera.height);
  Result<std::unique_ptr<GlVolumeRenderer>> volume_renderer = GlVolumeRenderer::create(scene);
  if (!volume_renderer) return volume_renderer.error();
  std::vector<Image> images;
  double exposure = 1;
  char text[96];
  for (const Volume& v : volumes) {
    progress.begin("render " + v.name + " volume");
    (*volume_renderer)->set_volume(v.mesh);
    double seconds = 0;
    images.push_back((*volume_renderer)->render(&seconds));
    if (images.size() == 1) exposure = percentile_exposure(images[0], 1.5);
    const std::string name = "airlight_" + v.name;
    if (Status s = write_image(out(name + ".exr"), images.back()); !s) return s;
    if (Status s = write_image(out(name + ".png"), images.back(), exposure); !s) return s;
    std::snprintf(text, sizeof text, "GPU %.1f ms", seconds * 1e3);
    std::string result = text;
    if (images.size() > 1) {
      std::snprintf(text, sizeof text, "; vs static: rel. L2 %.2e",
                    compare_images(images.back(), images[0]).relative_l2);
      result += text;
    }
    summary.add("render " + v.name + " (volume)", name + ".png", size, result);
  }
  MarchOptions march;
  march.samples = 128;
  march.interleave = 2;
  Result<std::unique_ptr<GlMarcher>> marcher =
      GlMarcher::create(scene, shadow.images(), shadow.sources(), march);
  if (!marcher) return marcher.error();
  progress.begin("render raymarch");
  double seconds = 0;
  const Image marched = (*marcher)->render(&seconds);
  if (Status s = write_image(out("airlight_raymarch.exr"), marched); !s) return s;
  if (Status s = write_image(out("airlight_raymarch.png"), marched, exposure); !s) return s;
  std::snprintf(text, sizeof text, "GPU %.1f ms; vs static: rel. L2 %.2e", seconds * 1e3,
                compare_images(marched, images[0]).relative_l2);
  summary.add("render raymarch 128x2x2", "airlight_raymarch.png", size, text);

  progress.begin("composite");
  // The picture: the surfaces the spot lights and the static volume's airlight in the light's
  // warm colour, the ambient light in a cool one, exposed so that the shafts keep their gradient.
  const MapSize map{shadow.width(), shadow.height()};
  SurfaceShading direct;
  direct.ambient = 0;
  SurfaceShading ambient;
  ambient.albedo = 0;
  ambient.ambient = kDemoAmbient;
  Image dark = images[0];
  std::fill(dark.values.begin(), dark.values.end(), 0.0);
  const Image lit =
      lit_surfaces(scene, shadow_pass.window[0], map.width, map.height, images[0], direct);
  const Image sky =
      lit_surfaces(scene, shadow_pass.window[0], map.width, map.height, dark, ambient);
  Image picture = lit;
  for (std::size_t i = 0; i < picture.values.size(); ++i) picture.values[i] += sky.values[i];
  std::array<Image, 3> rgb{lit, lit, lit};
  for (std::size_t k = 0; k < 3; ++k)
    for (std::size_t i = 0; i < lit.values.size(); ++i)
      rgb[k].values[i] = kLightColour[k] * lit.values[i] + kAmbientColour[k] * sky.values[i];
  if (Status s = write_rgb_image(out("demo.png"), rgb[0], rgb[1], rgb[2],
                                 percentile_exposure(picture, kDemoExposure));
      !s)
    return s;
  summary.add("picture", "demo.png", size, "lit surfaces + static volume's airlight");
  progress.begin("fog picture");
  const Result<FogPicture> fog_picture =
      write_fog_picture(scene, volumes[0].mesh, fog, shadow_pass.window[0], map.width, map.height,
                        out("demo_fog.png"), {}, &images[0]);
  if (!fog_picture) return fog_picture.error();
  std::snprintf(text, sizeof text, "GPU %.1f ms; noise fog (right) beside demo.png's medium",
                fog_picture->fog_seconds * 1e3);
  summary.add("fog picture", "demo_fog.png", size_text(2 * scene.camera.width, scene.camera.height),
              text);
  return {};
}
#endif

int run_demo(const DemoOptions& o) {
  const std::string data = find_data_dir(o.data_dir);
  std::error_code ec;
  fs::create_directories(o.out_dir, ec);
  if (!fs::is_directory(o.out_dir)) return fail(o.out_dir + ": cannot create the output directory");
  const auto out = [&](const std::string& name) { return o.out_dir + "/" + name; };
  Progress progress(o.quiet);
  Summary summary(progress);

  const std::string scene_path = data + "/sponza_crop.ply";
  progress.begin("reading " + scene_path);
  Result<DemoScene> scene = load_demo_scene(data, o.size);
  if (!scene) return fail(scene.error());
  progress.end();
  const Light& light = scene->light;
  const Camera& camera = scene->camera;

  // ---- depth passes -----------------------------------------------------------------------------
  std::string why_not_gl;
  const std::unique_ptr<DepthPasses> passes =
      open_depth_passes(scene->mesh, scene_path, &why_not_gl);
  const bool gl = why_not_gl.empty();
  const Result<MapSize> size = shadow_map_size(light, o.size, data + "/sponza_demo_spot.json");
  if (!size) return fail(size.error());
  progress.begin("shadow map");
  Result<RenderedPasses> shadow_pass = depth_pass(*passes, light, *size, out("shadow_map"));
  if (!shadow_pass) return fail(shadow_pass.error());
  const ShadowMaps shadow = ShadowMaps::planar(shadow_pass->maps.image, "shadow_map.exr");
  summary.add("shadow map " + size_text(size->width, size->height), "shadow_map.exr",
              thousands(scene->mesh.num_triangles()) + " scene",
              gl ? passes->method() : passes->method() + " (" + why_not_gl + ")");

  progress.begin("camera depth");
  Result<RenderedPasses> camera_pass =
      depth_pass(*passes, camera.view, {camera.width, camera.height}, out("camera_depth"));
  if (!camera_pass) return fail(camera_pass.error());
  summary.add("camera depth " + size_text(camera.width, camera.height), "camera_depth.exr", "", "");

  // ---- volumes ----------------------------------------------------------------------------------
  std::vector<Summary::Row> checks;
  Result<std::vector<Volume>> volumes =
      build_volumes(light, shadow, data + "/sponza_demo_spot.json", o.max_error, o.out_dir,
                    progress, summary, &checks);
  if (!volumes) return fail(volumes.error());
  progress.begin("web viewer inputs");
  if (Status s = write_viewer_inputs(data, o.out_dir, scene->mesh, light, camera, *volumes); !s)
    return fail(s.error());
  summary.add("web viewer inputs", "volume_static.glb", "",
              "+ adaptive, scene, camera, medium, light");
  for (Summary::Row& check : checks) summary.row(std::move(check));

    // ---- rendering
    // --------------------------------------------------------------------------------
#ifdef LIGHTVOL_HAS_SHADOWMAP
  if (gl) {
    RenderScene render_scene{camera, {}, light, scene->medium};
    const DepthImage& camera_depth = camera_pass->maps.image;
    Result<std::vector<double>> surface = surface_distances(
        camera, camera_depth.values, camera_depth.width, camera_depth.height, "camera_depth.exr");
    if (!surface) return fail(surface.error());
    render_scene.surface = std::move(*surface);
    if (Status s = render_pictures(render_scene, scene->fog, *volumes, shadow, *shadow_pass,
                                   o.out_dir, progress, summary);
        !s)
      return fail(s.error());
  } else {
    summary.skipped("render", "no OpenGL (" + why_not_gl + ")");
  }
#else
  summary.skipped("render", "built without OpenGL");
#endif

  if (!o.quiet) summary.print(o.out_dir);
  const fs::path serve = fs::path(data).parent_path() / "web" / "serve.mjs";
  if (!o.quiet && fs::exists(serve))
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
  auto o = std::make_shared<DemoOptions>();
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
  cmd->callback([o, run] { *run = [o] { return run_demo(*o); }; });
}

}  // namespace lightvol::cli
