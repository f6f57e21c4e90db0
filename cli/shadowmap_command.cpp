// lightvol shadowmap: a scene mesh → the depth image(s) a renderer's shadow-map pass would store
// (or, with --camera, the camera depth that `lightvol render --depth` reads).
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <lightvol/core/atomic_file.h>
#include <lightvol/core/limits.h>
#include <lightvol/core/mesh.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/depth/shadow_maps.h>
#include <lightvol/light/camera.h>
#include <lightvol/light/light.h>
#include <lightvol/scene/depth_passes.h>
#include <lightvol/scene/scene.h>
#include <lightvol/scene/shadowmap.h>

#include "commands.h"
#include "progress.h"

namespace lightvol::cli {
namespace {

struct ShadowmapOptions {
  std::string scene_path;
  std::string light_path;
  std::string camera_path;
  int size = 0;
  std::string out_path;
  std::string preview_path;
  bool cpu = false;
  bool quiet = false;
};

// The view to render (a light, or a camera's view) and its size; `what` names it in the summary.
struct View {
  Light light;
  MapSize size;
  std::string what;
};

Result<View> load_view(const ShadowmapOptions& o) {
  if (o.light_path.empty() == o.camera_path.empty())
    return Error{"give exactly one of --light LIGHT.json and --camera CAMERA.json"};
  View v;
  if (!o.light_path.empty()) {
    if (o.size == 0)
      return Error{"--size: required with --light (the shadow map's width in texels)"};
    Result<Light> light = load_light(o.light_path);
    if (!light) return light.error();
    v.light = *light;
    Result<MapSize> size = shadow_map_size(v.light, o.size, o.light_path);
    if (!size) return size.error();
    v.size = *size;
    v.what = std::string(to_string(v.light.type)) + " light";
  } else {
    if (o.size != 0) return Error{"--size: the camera's \"width\" and \"height\" give the size"};
    Result<Camera> camera = load_camera(o.camera_path);
    if (!camera) return camera.error();
    v.light = camera->view;
    v.size = {camera->width, camera->height};
    v.what = "camera";
  }
  if (o.out_path.find("{face}") != std::string::npos && v.light.type != LightType::omni)
    return Error{o.out_path + ": {face} applies to omni lights only"};
  if (Status m =
          check_memory(shadow_map_memory_bytes(v.size.width, v.size.height, pass_count(v.light)),
                       o.light_path.empty() ? o.camera_path : o.light_path,
                       "a " + size_text(v.size.width, v.size.height) + " shadow map");
      !m)
    return m.error();
  return v;
}

int run_shadowmap(const ShadowmapOptions& o) {
  Result<View> view = load_view(o);
  if (!view) return fail(view.error());
  const MapSize size = view->size;

  Progress progress(o.quiet);
  progress.begin("reading " + o.scene_path);
  Result<Mesh> scene = load_scene(o.scene_path);
  if (!scene) return fail(scene.error());
  progress.end(std::to_string(scene->num_triangles()) + " triangles");

  const int passes = pass_count(view->light);
  progress.begin("rendering " + std::to_string(passes) + " depth pass" +
                 (passes > 1 ? "es " : " ") + size_text(size.width, size.height) +
                 (o.cpu ? " (CPU ray casting)" : ""));
  std::unique_ptr<DepthPasses> renderer;
  if (o.cpu) {
    renderer = cpu_depth_passes(*scene);
  } else {
    Result<std::unique_ptr<DepthPasses>> gl = gl_depth_passes(*scene, o.scene_path);
    if (!gl) return fail(gl.error().message + " (--cpu renders by ray casting without OpenGL)");
    renderer = std::move(*gl);
  }
  Result<RenderedPasses> rendered = render_passes(*renderer, view->light, size);
  if (!rendered) return fail(rendered.error());
  progress.end();

  progress.begin("writing " + o.out_path);
  OutputTransaction outputs;  // the faces and the preview appear together, or none does
  Result<std::vector<std::string>> written = write_shadow_maps(o.out_path, rendered->maps);
  if (!written) return fail(written.error());
  if (!o.preview_path.empty()) {
    if (Status s = write_depth_image(
            o.preview_path, depth_preview(view->light, size.width, size.height, rendered->window));
        !s)
      return fail(s.error());
  }
  if (Status s = outputs.commit(); !s) return fail(s.error());
  progress.end();

  if (!o.quiet) {
    std::printf(
        "wrote %s: %s %dx%d%s, %s depth, %.1f%% of texels hit, %s triangles%s\n",
        written->size() > 1 ? (std::to_string(written->size()) + " files " + o.out_path).c_str()
                            : written->front().c_str(),
        view->what.c_str(), size.width, size.height, passes > 1 ? " x 6 faces" : "",
        std::string(to_string(view->light.depth)).c_str(), 100.0 * rendered->hit_fraction(),
        thousands(scene->num_triangles()).c_str(),
        o.cpu ? ""
              : (", GPU " + std::to_string(rendered->gpu_seconds * 1e3).substr(0, 6) + " ms")
                    .c_str());
  }
  return 0;
}

}  // namespace

void add_shadowmap_command(CLI::App& app, Runner* run) {
  auto o = std::make_shared<ShadowmapOptions>();
  CLI::App* cmd = app.add_subcommand(
      "shadowmap", "Render a scene mesh's shadow map(s), or a camera's depth, headless.");
  cmd->footer(
      "Examples:\n"
      "  lightvol shadowmap sponza.obj --light spot.json --size 1024 --out shadow.exr\n"
      "  lightvol shadowmap sponza.obj --light omni.json --size 512 --out 'cube_{face}.exr'\n"
      "  lightvol shadowmap sponza.obj --camera camera.json --out camera_depth.exr\n"
      "Depth is rendered with OpenGL (EGL, headless) in float window depth at texel centres and\n"
      "stored in the light's \"depth\" encoding. Sizes: spot N wide x round(N/aspect) high;\n"
      "directional N x N; omni six N x N faces +X -X +Y -Y +Z -Z, as files when the output path\n"
      "has {face} (px nx py ny pz nz), else one N x 6N strip. First row = top of the view unless\n"
      "flip_y. Scenes: OBJ, PLY, OFF, STL, DRC, GLB.");
  cmd->add_option("scene", o->scene_path, "Scene mesh (OBJ, PLY, OFF, STL, DRC, GLB)")->required();
  cmd->add_option("--light", o->light_path, "Light description (LIGHT.json)");
  cmd->add_option("--camera", o->camera_path,
                  "Camera description (a spot light's keys plus width, height): render its depth");
  cmd->add_option("--size", o->size, "Shadow-map width in texels (with --light)")
      ->check(decimal_integer());
  cmd->add_option("--out,-o", o->out_path, "Output depth image (EXR, TIFF, PFM, PNG-16)")
      ->required();
  cmd->add_option("--preview", o->preview_path,
                  "Also write a PNG for people: near = white, far = dark, nothing hit = black");
  cmd->add_flag("--cpu", o->cpu, "Ray-cast on the CPU (double precision) instead of OpenGL");
  cmd->add_flag("--quiet,-q", o->quiet, "No progress lines and no summary");
  cmd->callback([o, run] { *run = [o] { return run_shadowmap(*o); }; });
}

}  // namespace lightvol::cli
