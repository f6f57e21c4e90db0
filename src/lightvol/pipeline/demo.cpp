#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <utility>

#include <nlohmann/json.hpp>

#include <lightvol/core/atomic_file.h>
#include <lightvol/core/text.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/export/export.h>
#include <lightvol/light/camera.h>
#include <lightvol/light/light.h>
#include <lightvol/pipeline/build_file.h>
#include <lightvol/pipeline/demo.h>
#include <lightvol/pipeline/detail/demo_rows.h>
#include <lightvol/scene/scene.h>

namespace lightvol {
namespace {
using detail::end_row;
using detail::size_text;
namespace fs = std::filesystem;

// The bundled scene, its spot light, camera and media.
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
  if (!mesh)
    return Error{mesh.error().message + " (is DemoOptions::data_dir the bundled data/ folder?)"};
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

// The static and the adaptive volume of the shadow map, each checked from the light and written
// as volume_NAME.ply (build_volume_file: nothing written when it fails its checks). Their rows go
// to `rows`, the rows of their checks to `checks` (for the table after the viewer's inputs).
Result<std::vector<DemoVolume>> build_volumes(const Light& light, const ShadowMaps& shadow,
                                              const std::string& light_path, double max_error,
                                              const std::string& out_dir, StageLog& log,
                                              std::vector<DemoRow>* rows,
                                              std::vector<DemoRow>* checks) {
  std::vector<DemoVolume> volumes;
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
    BuildFileResult built = build_volume_file(options, log);
    if (!built.status) return built.status.error();
    char error_text[64];
    std::snprintf(error_text, sizeof error_text, "max error %g", max_error);
    rows->push_back({name + " volume", file, thousands(built.triangles) + " tris",
                     adaptive ? error_text : "", built.seconds.build + built.seconds.write});
    checks->push_back({"check " + name, "", "",
                       "valid (" + std::string(to_string(built.check.proof)) + ")",
                       built.seconds.check});
    volumes.push_back({name, std::move(built.mesh)});
  }
  return volumes;
}

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// What the web viewer (web/) needs beside the demo's other outputs: the volumes as GLBs carrying
// their light and the medium, the scene as a GLB, the camera (at the demo's image size) and the
// medium; the live page (web/live.html) also the light (light.json, the demo's spot).
Status write_viewer_inputs(const std::string& data, const std::string& dir, const Mesh& scene,
                           const Light& light, const Camera& camera,
                           const std::vector<DemoVolume>& volumes) {
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
  for (const DemoVolume& v : volumes)
    if (Status s = write_mesh(dir + "/volume_" + v.name + ".glb", v.mesh, options); !s) return s;
  if (Status s = write_mesh(dir + "/scene.glb", scene); !s) return s;
  const std::string camera_text =
      camera_json.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
  if (Status s = write_bytes_atomically(dir + "/camera.json", camera_text); !s) return s;
  if (Status s =
          write_bytes_atomically(dir + "/light.json", slurp(data + "/sponza_demo_spot.json"));
      !s)
    return s;
  return write_bytes_atomically(dir + "/medium.json", medium_text);
}

}  // namespace

Result<DemoReport> run_demo(const DemoOptions& o, StageLog& log) {
  const std::string& data = o.data_dir;
  std::error_code ec;
  fs::create_directories(o.out_dir, ec);
  if (!fs::is_directory(o.out_dir, ec))
    return Error{o.out_dir + ": cannot create the output directory"};
  const auto out = [&](const std::string& name) { return o.out_dir + "/" + name; };
  DemoReport report;
  std::vector<DemoRow>& rows = report.rows;

  const std::string scene_path = data + "/sponza_crop.ply";
  log.begin("reading " + scene_path);
  Result<DemoScene> scene = load_demo_scene(data, o.size);
  if (!scene) return scene.error();
  log.end();
  const Light& light = scene->light;
  const Camera& camera = scene->camera;

  // Depth passes on the GPU when an OpenGL context can be made (it stays current for the
  // pictures), else by CPU ray casting; `why_not_gl` says why not.
  std::string why_not_gl = "built without OpenGL (LIGHTVOL_WITH_GL=OFF)";
  std::unique_ptr<DepthPasses> passes;
  if (o.gpu.depth_passes) {
    Result<std::unique_ptr<DepthPasses>> gl = o.gpu.depth_passes(scene->mesh, scene_path);
    if (gl) {
      passes = std::move(*gl);
      why_not_gl.clear();
    } else {
      why_not_gl = gl.error().message;
    }
  }
  if (!passes) passes = cpu_depth_passes(scene->mesh);
  const bool gl = why_not_gl.empty();
  const std::string light_path = data + "/sponza_demo_spot.json";
  const Result<MapSize> size = shadow_map_size(light, o.size, light_path);
  if (!size) return size.error();
  log.begin("shadow map");
  Result<RenderedPasses> shadow_pass = depth_pass(*passes, light, *size, out("shadow_map"));
  if (!shadow_pass) return shadow_pass.error();
  const ShadowMaps shadow = ShadowMaps::planar(shadow_pass->maps.image, "shadow_map.exr");
  end_row(log, &rows,
          {"shadow map " + size_text(size->width, size->height), "shadow_map.exr",
           thousands(scene->mesh.num_triangles()) + " scene",
           gl ? passes->method() : passes->method() + " (" + why_not_gl + ")"});

  log.begin("camera depth");
  Result<RenderedPasses> camera_pass =
      depth_pass(*passes, camera.view, {camera.width, camera.height}, out("camera_depth"));
  if (!camera_pass) return camera_pass.error();
  end_row(log, &rows,
          {"camera depth " + size_text(camera.width, camera.height), "camera_depth.exr", "", ""});

  std::vector<DemoRow> checks;
  Result<std::vector<DemoVolume>> volumes =
      build_volumes(light, shadow, light_path, o.max_error, o.out_dir, log, &rows, &checks);
  if (!volumes) return volumes.error();
  log.begin("web viewer inputs");
  if (Status s = write_viewer_inputs(data, o.out_dir, scene->mesh, light, camera, *volumes); !s)
    return s.error();
  end_row(
      log, &rows,
      {"web viewer inputs", "volume_static.glb", "", "+ adaptive, scene, camera, medium, light"});
  for (DemoRow& check : checks) rows.push_back(std::move(check));

  if (!o.gpu.pictures) {
    rows.push_back({"render", "", "", "skipped: built without OpenGL", 0});
    return report;
  }
  if (!gl) {
    rows.push_back({"render", "", "", "skipped: no OpenGL (" + why_not_gl + ")", 0});
    return report;
  }
  RenderScene render_scene{camera, {}, light, scene->medium};
  const DepthImage& camera_depth = camera_pass->maps.image;
  Result<std::vector<double>> surface = surface_distances(
      camera, camera_depth.values, camera_depth.width, camera_depth.height, "camera_depth.exr");
  if (!surface) return surface.error();
  render_scene.surface = std::move(*surface);
  const DemoPictureInputs pictures{render_scene,           scene->fog, *volumes, shadow,
                                   shadow_pass->window[0], o.out_dir};
  if (Status s = o.gpu.pictures(pictures, log, &rows); !s) return s.error();
  return report;
}

std::string demo_table(const DemoReport& report) {
  std::string text;
  char line[512];
  std::snprintf(line, sizeof line, "%-26s %-22s %-18s %8s  %s\n", "step", "output", "size", "time",
                "result");
  text += line;
  for (const DemoRow& r : report.rows) {
    // The columns padded as printf pads them; the result in full, whatever its length.
    std::snprintf(line, sizeof line, "%-26s %-22s %-18s %7.2fs  ", r.step.c_str(), r.file.c_str(),
                  r.size.c_str(), r.seconds);
    text += line;
    text += r.result + "\n";
  }
  return text;
}

}  // namespace lightvol
