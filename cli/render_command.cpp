// lightvol render: the OpenGL checker. Renders the signed single-scattering airlight of a light
// volume (or, for comparison, ray marching and radial blur from the shadow maps) from a camera.
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include <lightvol/airlight/airlight.h>
#include <lightvol/core/mesh.h>
#include <lightvol/depth/cube_faces.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/io/mesh_reader.h>
#include <lightvol/light/light.h>
#include <lightvol/render/image_io.h>
#include <lightvol/render/reference.h>
#include <lightvol/render/scene.h>
#ifdef LIGHTVOL_WITH_GL
#include <lightvol/gl/context.h>
#include <lightvol/render/gl_marchers.h>
#include <lightvol/render/gl_volume.h>
#endif

#include "commands.h"
#include "progress.h"

namespace lightvol::cli {
namespace {

struct RenderOptions {
  std::string mesh_path;
  std::string light_path;
  std::string camera_path;
  std::string depth_path;
  std::string medium_path;
  std::string out_path;
  std::string method = "volume";
  std::vector<std::string> shadow_maps;
  std::string channel;
  int samples = 64;
  int interleave = 1;
  bool composite = false;
  double background = 0.1;
  double exposure = 0;
  std::string compare_path;
  int frames = 0;
  bool quiet = false;
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty()
             ? 0
             : (v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]));
}

int run_render(const RenderOptions& o) {
  Progress progress(o.quiet);
  const bool needs_mesh = o.method == "volume" || o.method == "reference";
  if (needs_mesh && o.mesh_path.empty())
    return fail("render: --method " + o.method + " needs the light volume MESH");
  if (o.method == "raymarch" && o.shadow_maps.empty())
    return fail("render: --method " + o.method +
                " needs --shadow-map DEPTH (the light's shadow map(s))");
  if (o.samples < 1) return fail("--samples: must be >= 1, got " + std::to_string(o.samples));
  if (o.interleave < 1)
    return fail("--interleave: must be >= 1, got " + std::to_string(o.interleave));
  if (o.frames < 0) return fail("--frames: must be >= 0, got " + std::to_string(o.frames));
  if (o.frames > 0 && o.method == "reference")
    return fail("--frames: times GPU work; --method reference runs on the CPU");

  // ---- inputs ----
  RenderScene scene;
  Result<Camera> camera = load_camera(o.camera_path);
  if (!camera) return fail(camera.error().message);
  scene.camera = *camera;
  Result<Light> light = load_light(o.light_path);
  if (!light) return fail(light.error().message);
  scene.light = *light;
  Result<Medium> medium = load_medium(o.medium_path);
  if (!medium) return fail(medium.error().message);
  scene.medium = *medium;
  if (scene.medium.profile.enabled() && scene.light.type != LightType::spot)
    return fail(o.medium_path + ": key 'profile': applies to spot lights only, " + o.light_path +
                " is a " + std::string(to_string(scene.light.type)) + " light");
  progress.begin("reading " + o.depth_path);
  Result<DepthImage> depth = read_depth_image(o.depth_path, {o.channel});
  if (!depth) return fail(depth.error().message);
  Result<std::vector<double>> surface =
      surface_distances(scene.camera, depth->values, depth->width, depth->height, o.depth_path);
  if (!surface) return fail(surface.error().message);
  scene.surface = std::move(*surface);
  progress.end(std::to_string(depth->width) + "x" + std::to_string(depth->height));

  Mesh volume;
  if (needs_mesh) {
    progress.begin("reading " + o.mesh_path);
    Result<Mesh> mesh = read_mesh(o.mesh_path);
    if (!mesh) return fail(mesh.error().message);
    volume = std::move(*mesh);
    progress.end(thousands(volume.num_triangles()) + " triangles");
  }

  // ---- render ----
  Image image;
  std::vector<double> frame_seconds;
  if (o.method == "reference") {
    progress.begin("rendering reference (CPU, double precision)");
    image = render_reference(volume, scene);
    progress.end();
  } else {
#ifdef LIGHTVOL_WITH_GL
    Result<std::unique_ptr<gl::Context>> context = gl::Context::create();
    if (!context) return fail(context.error().message);
    progress.begin("rendering " + o.method + " on " + (*context)->renderer());
    if (o.method == "volume") {
      Result<std::unique_ptr<GlVolumeRenderer>> renderer = GlVolumeRenderer::create(scene);
      if (!renderer) return fail(renderer.error().message);
      (*renderer)->set_volume(volume);
      image = (*renderer)->render();
      for (int i = 0; i < o.frames; ++i) {
        double s = 0;
        (*renderer)->render(&s);
        frame_seconds.push_back(s);
      }
    } else {
      // Omni maps: six files, one path with {face}, or one W x 6W strip (docs/design.md §2).
      std::vector<std::string> paths = o.shadow_maps;
      if (scene.light.type == LightType::omni && paths.size() == 1 &&
          paths[0].find("{face}") != std::string::npos) {
        const std::string pattern = paths[0];
        paths.clear();
        for (int f = 0; f < kOmniFaces; ++f) paths.push_back(expand_face_pattern(pattern, f));
      }
      std::vector<DepthImage> maps;
      std::vector<std::string> sources;
      for (const std::string& path : paths) {
        Result<DepthImage> map = read_depth_image(path, {o.channel});
        if (!map) return fail(map.error().message);
        maps.push_back(std::move(*map));
        sources.push_back(path);
      }
      if (scene.light.type == LightType::omni && maps.size() == 1) {
        Result<CubeFaces> cube = split_cube_strip(maps[0], paths[0]);
        if (!cube) return fail(cube.error().message);
        maps.assign(cube->faces.begin(), cube->faces.end());
        sources.assign(cube->sources.begin(), cube->sources.end());
      }
      MarchOptions mo;
      mo.samples = o.samples;
      mo.interleave = o.interleave;
      mo.method = o.method == "radial" ? MarchMethod::radial : MarchMethod::raymarch;
      Result<std::unique_ptr<GlMarcher>> marcher = GlMarcher::create(scene, maps, sources, mo);
      if (!marcher) return fail(marcher.error().message);
      image = (*marcher)->render();
      for (int i = 0; i < o.frames; ++i) {
        double s = 0;
        (*marcher)->render(&s);
        frame_seconds.push_back(s);
      }
    }
    progress.end();
#else
    return fail("--method " + o.method +
                ": this lightvol was built without OpenGL (LIGHTVOL_WITH_GL=OFF)");
#endif
  }

  if (o.composite) {
    // Surfaces of constant radiance `background` seen through the medium.
    const double st = scene.medium.extinction();
    for (std::size_t i = 0; i < image.values.size(); ++i)
      image.values[i] += o.background * std::exp(-st * scene.surface[i]);
  }

  // ---- outputs ----
  progress.begin("writing " + o.out_path);
  if (Status s = write_image(o.out_path, image, o.exposure); !s) return fail(s.error().message);
  progress.end();

  double sum = 0, peak = 0;
  for (double v : image.values) {
    sum += v;
    peak = std::max(peak, std::abs(v));
  }
  std::printf("%s: %dx%d airlight, method %s, mean %.6g, max %.6g\n", o.out_path.c_str(),
              image.width, image.height, o.method.c_str(),
              image.values.empty() ? 0.0 : sum / static_cast<double>(image.values.size()), peak);
  if (!frame_seconds.empty())
    std::printf("time per frame: %.3f ms (median of %zu frames)\n", 1e3 * median(frame_seconds),
                frame_seconds.size());
  if (!o.compare_path.empty()) {
    Result<Image> ref = read_image(o.compare_path);
    if (!ref) return fail(ref.error().message);
    if (ref->width != image.width || ref->height != image.height)
      return fail(o.compare_path + ": image is " + std::to_string(ref->width) + "x" +
                  std::to_string(ref->height) + ", the render is " + std::to_string(image.width) +
                  "x" + std::to_string(image.height));
    const ImageDifference d = compare_images(image, *ref);
    std::printf("compared with %s: relative L2 %.3e, max abs error %.3e, PSNR %.2f dB\n",
                o.compare_path.c_str(), d.relative_l2, d.max_abs, d.psnr_db);
  }
  return 0;
}

}  // namespace

void add_render_command(CLI::App& app, Runner* run) {
  auto o = std::make_shared<RenderOptions>();
  CLI::App* cmd = app.add_subcommand(
      "render",
      "The OpenGL checker: render the single-scattering airlight of a light volume (signed\n"
      "additive blending, --method volume), its CPU reference, or the ray-marching (from the "
      "shadow\n"
      "map) and radial-blur (from the camera depth) alternatives.");
  cmd->add_option("MESH", o->mesh_path, "Light volume (world space), for volume and reference");
  cmd->add_option("--light", o->light_path, "Light description (JSON)")->required();
  cmd->add_option("--camera", o->camera_path, "Camera: a spot light description plus width, height")
      ->required();
  cmd->add_option("--depth", o->depth_path, "Camera depth image (encoding: the camera's \"depth\")")
      ->required();
  cmd->add_option("--medium", o->medium_path,
                  "Medium: {scattering, absorption, intensity, phase {type, g|k}}")
      ->required();
  cmd->add_option("--out", o->out_path,
                  "Output image: .exr keeps linear floats, .png is tone-mapped")
      ->required();
  cmd->add_option("--method", o->method, "volume | reference | raymarch | radial")
      ->check(CLI::IsMember({"volume", "reference", "raymarch", "radial"}))
      ->capture_default_str();
  cmd->add_option(
      "--shadow-map", o->shadow_maps,
      "raymarch: the light's shadow map (omni: six faces, a {face} path or a W x 6W strip)");
  cmd->add_option("--channel", o->channel, "Channel of the depth images (EXR Z, R, ...)");
  cmd->add_option("--samples", o->samples, "raymarch: steps per pixel; radial: blur samples")
      ->capture_default_str();
  cmd->add_option("--interleave", o->interleave, "raymarch: M for M x M interleaved sampling")
      ->capture_default_str();
  cmd->add_flag("--composite", o->composite,
                "Add surfaces of radiance --background seen through the medium");
  cmd->add_option("--background", o->background, "Surface radiance for --composite")
      ->capture_default_str();
  cmd->add_option("--exposure", o->exposure, "PNG: scale before tone mapping (default: automatic)");
  cmd->add_option("--compare", o->compare_path,
                  "Print relative L2, max abs error and PSNR against this .exr");
  cmd->add_option("--frames", o->frames,
                  "Render K more frames and print the median GPU time per frame");
  cmd->add_flag("--quiet", o->quiet, "No progress lines");
  cmd->callback([o, run] { *run = [o] { return run_render(*o); }; });
}

}  // namespace lightvol::cli
