// lightvol shadowmap: a scene mesh → the depth image(s) a renderer's shadow-map pass would store
// (or, with --camera, the camera depth that `lightvol render --depth` reads).
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <lightvol/airlight/airlight.h>
#include <lightvol/core/limits.h>
#include <lightvol/core/mesh.h>
#include <lightvol/depth/cube_faces.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/gl/context.h>
#include <lightvol/light/light.h>
#include <lightvol/scene/bvh.h>
#include <lightvol/scene/raycast.h>
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

int run_shadowmap(const ShadowmapOptions& o) {
  if (o.light_path.empty() == o.camera_path.empty())
    return fail("give exactly one of --light LIGHT.json and --camera CAMERA.json");
  const bool has_face = o.out_path.find("{face}") != std::string::npos;

  // The view to render and its size.
  Light light;
  MapSize size;
  std::string what;
  if (!o.light_path.empty()) {
    if (o.size == 0)
      return fail("--size: required with --light (the shadow map's width in texels)");
    Result<Light> l = load_light(o.light_path);
    if (!l) return fail(l.error().message);
    light = *l;
    Result<MapSize> s = shadow_map_size(light, o.size, o.light_path);
    if (!s) return fail(s.error().message);
    size = *s;
    what = std::string(to_string(light.type)) + " light";
  } else {
    if (o.size != 0) return fail("--size: the camera's \"width\" and \"height\" give the size");
    Result<Camera> camera = load_camera(o.camera_path);
    if (!camera) return fail(camera.error().message);
    light = camera->view;
    size = {camera->width, camera->height};
    what = "camera";
  }
  if (has_face && light.type != LightType::omni)
    return fail(o.out_path + ": {face} applies to omni lights only");
  if (Status m = check_memory(
          shadow_map_memory_bytes(size.width, size.height, pass_count(light)),
          o.light_path.empty() ? o.camera_path : o.light_path,
          "a " + std::to_string(size.width) + "x" + std::to_string(size.height) + " shadow map");
      !m)
    return fail(m.error().message);

  Progress progress(o.quiet);
  progress.begin("reading " + o.scene_path);
  Result<Mesh> scene = load_scene(o.scene_path);
  if (!scene) return fail(scene.error().message);
  progress.end(std::to_string(scene->num_triangles()) + " triangles");

  const int passes = pass_count(light);
  std::vector<std::vector<float>> window(static_cast<std::size_t>(passes));
  double gpu_seconds = 0;
  progress.begin("rendering " + std::to_string(passes) + " depth pass" +
                 (passes > 1 ? "es " : " ") + std::to_string(size.width) + "x" +
                 std::to_string(size.height) + (o.cpu ? " (CPU ray casting)" : ""));
  if (o.cpu) {
    const Bvh bvh(*scene);
    for (int face = 0; face < passes; ++face) {
      const std::vector<double> d = raycast_window_depth(bvh, light, size.width, size.height, face);
      window[static_cast<std::size_t>(face)].assign(d.begin(), d.end());
    }
  } else {
    Result<std::unique_ptr<gl::Context>> context = gl::Context::create();
    if (!context)
      return fail(context.error().message + " (--cpu renders by ray casting without OpenGL)");
    Result<ShadowMapRenderer> renderer = ShadowMapRenderer::create(*scene);
    if (!renderer) return fail(o.scene_path + ": " + renderer.error().message);
    for (int face = 0; face < passes; ++face) {
      double seconds = 0;
      Result<std::vector<float>> d =
          renderer->render_window_depth(light, size.width, size.height, face, &seconds);
      if (!d) return fail(d.error().message);
      window[static_cast<std::size_t>(face)] = std::move(*d);
      gpu_seconds += seconds;
    }
  }
  progress.end();

  std::size_t hit = 0, total = 0;
  for (const std::vector<float>& pass : window) {
    for (const float d : pass) hit += d < 1.0f ? 1 : 0;
    total += pass.size();
  }

  progress.begin("writing " + o.out_path);
  std::vector<std::string> written;
  if (light.type == LightType::omni) {
    CubeFaces cube;
    for (int face = 0; face < kOmniFaces; ++face)
      cube.faces[static_cast<std::size_t>(face)] =
          encode_depth(light, size.width, size.height, window[static_cast<std::size_t>(face)]);
    if (has_face) {
      for (int face = 0; face < kOmniFaces; ++face) {
        const std::string path = expand_face_pattern(o.out_path, face);
        if (Status s = write_depth_image(path, cube.faces[static_cast<std::size_t>(face)]); !s)
          return fail(s.error().message);
        written.push_back(path);
      }
    } else {
      if (Status s = write_depth_image(o.out_path, stack_cube_faces(cube)); !s)
        return fail(s.error().message);
      written.push_back(o.out_path);
    }
  } else {
    if (Status s =
            write_depth_image(o.out_path, encode_depth(light, size.width, size.height, window[0]));
        !s)
      return fail(s.error().message);
    written.push_back(o.out_path);
  }
  if (!o.preview_path.empty()) {
    if (Status s = write_depth_image(o.preview_path,
                                     depth_preview(light, size.width, size.height, window));
        !s)
      return fail(s.error().message);
  }
  progress.end();

  if (!o.quiet) {
    std::printf(
        "wrote %s: %s %dx%d%s, %s depth, %.1f%% of texels hit, %s triangles%s\n",
        written.size() > 1 ? (std::to_string(written.size()) + " files " + o.out_path).c_str()
                           : written[0].c_str(),
        what.c_str(), size.width, size.height, passes > 1 ? " x 6 faces" : "",
        std::string(to_string(light.depth)).c_str(),
        100.0 * static_cast<double>(hit) / static_cast<double>(total),
        thousands(scene->num_triangles()).c_str(),
        o.cpu ? "" : (", GPU " + std::to_string(gpu_seconds * 1e3).substr(0, 6) + " ms").c_str());
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
  cmd->add_option("--size", o->size, "Shadow-map width in texels (with --light)");
  cmd->add_option("--out,-o", o->out_path, "Output depth image (EXR, TIFF, PFM, PNG-16)")
      ->required();
  cmd->add_option("--preview", o->preview_path,
                  "Also write a PNG for people: near = white, far = dark, nothing hit = black");
  cmd->add_flag("--cpu", o->cpu, "Ray-cast on the CPU (double precision) instead of OpenGL");
  cmd->add_flag("--quiet,-q", o->quiet, "No progress lines and no summary");
  cmd->callback([o, run] { *run = [o] { return run_shadowmap(*o); }; });
}

}  // namespace lightvol::cli
