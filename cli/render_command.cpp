// lightvol render: the OpenGL checker. Renders the signed single-scattering airlight of a light
// volume (or, for comparison, ray marching and radial blur from the shadow maps) from a camera.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <lightvol/airlight/airlight.h>
#include <lightvol/core/mesh.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/depth/shadow_maps.h>
#include <lightvol/io/mesh_reader.h>
#include <lightvol/light/camera.h>
#include <lightvol/light/light.h>
#include <lightvol/render/image_io.h>
#include <lightvol/render/reference.h>
#include <lightvol/render/scene.h>
#include <lightvol/render/surfaces.h>
#ifdef LIGHTVOL_WITH_GL
#include <lightvol/gl/context.h>
#include <lightvol/render/gl_marchers.h>
#include <lightvol/render/gl_volume.h>
#include <lightvol/render/live_volume.h>
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
  bool adaptive = false;  // live: the adaptive volume at --max-error
  double max_error = -1;
  // media of varying density
  int grid_tile = 0;
  int grid_slices = 128;
  int opacity_size = 64;
  int opacity_layers = 64;
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty()
             ? 0
             : (v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]));
}

bool needs_mesh(const RenderOptions& o) { return o.method == "volume" || o.method == "reference"; }

// Flag combinations that make no sense; "" when the flags agree.
std::string conflicting_flags(const RenderOptions& o) {
  if (needs_mesh(o) && o.mesh_path.empty())
    return "render: --method " + o.method + " needs the light volume MESH";
  if ((o.method == "raymarch" || o.method == "live") && o.shadow_maps.empty())
    return "render: --method " + o.method + " needs --shadow-map DEPTH (the light's shadow map(s))";
  if (o.method == "live" && !o.mesh_path.empty())
    return "render: --method live makes the volume from --shadow-map on the GPU; it takes no MESH";
  if (o.adaptive && o.method != "live")
    return "--adaptive: applies with --method live only (--method volume draws the MESH given)";
  if (o.adaptive && o.max_error < 0)
    return "--adaptive: needs --max-error E (world units along the texel rays)";
  if (!o.adaptive && o.max_error >= 0) return "--max-error: applies with --adaptive only";
  if (o.samples < 1) return "--samples: must be >= 1, got " + std::to_string(o.samples);
  if (o.interleave < 1) return "--interleave: must be >= 1, got " + std::to_string(o.interleave);
  if (o.frames < 0) return "--frames: must be >= 0, got " + std::to_string(o.frames);
  if (o.grid_tile < 0 || o.grid_tile > 256)
    return "--grid-tile: must be in [0, 256], got " + std::to_string(o.grid_tile);
  if (o.grid_slices < 2 || o.grid_slices > 4096)
    return "--grid-slices: must be in [2, 4096], got " + std::to_string(o.grid_slices);
  if (o.opacity_size < 2 || o.opacity_size > 1024)
    return "--opacity-size: must be in [2, 1024], got " + std::to_string(o.opacity_size);
  if (o.opacity_layers < 2 || o.opacity_layers > 4096)
    return "--opacity-layers: must be in [2, 4096], got " + std::to_string(o.opacity_layers);
  if (o.frames > 0 && o.method == "reference")
    return "--frames: times GPU work; --method reference runs on the CPU";
  return "";
}

// The camera, light and medium, and the surface distances of the camera depth.
Result<RenderScene> load_render_scene(const RenderOptions& o, Progress& progress) {
  RenderScene scene;
  Result<Camera> camera = load_camera(o.camera_path);
  if (!camera) return camera.error();
  scene.camera = *camera;
  Result<Light> light = load_light(o.light_path);
  if (!light) return light.error();
  scene.light = *light;
  Result<Medium> medium = load_medium(o.medium_path);
  if (!medium) return medium.error();
  scene.medium = *medium;
  if (scene.medium.profile.enabled() && scene.light.type != LightType::spot)
    return Error{o.medium_path + ": key 'profile': applies to spot lights only, " + o.light_path +
                 " is a " + std::string(to_string(scene.light.type)) + " light"};
  if (scene.medium.density.varying() && o.method != "reference" && o.method != "volume" &&
      o.method != "raymarch")
    return Error{o.medium_path + ": key 'density': --method " + o.method +
                 " renders homogeneous media only (volume, reference and raymarch take a density)"};
  progress.begin("reading " + o.depth_path);
  Result<DepthImage> depth = read_depth_image(o.depth_path, {o.channel});
  if (!depth) return depth.error();
  Result<std::vector<double>> surface =
      surface_distances(scene.camera, depth->values, depth->width, depth->height, o.depth_path);
  if (!surface) return surface.error();
  scene.surface = std::move(*surface);
  progress.end(size_text(depth->width, depth->height));
  return scene;
}

#ifdef LIGHTVOL_WITH_GL
// Renders once, then `frames` more times, timing those.
template <class Renderer>
Image render_frames(Renderer& renderer, int frames, std::vector<double>* frame_seconds) {
  Image image = renderer.render();
  for (int i = 0; i < frames; ++i) {
    double s = 0;
    renderer.render(&s);
    frame_seconds->push_back(s);
  }
  return image;
}
#endif

// The airlight by --method: the CPU reference, or on the GPU the volume, ray marching or the
// radial blur.
// `generation_seconds` receives, for --method live with --frames K, K timings of the volume's
// generation alone (LiveVolume::generate and glFinish: the paper's "tessellate" row).
Result<Image> render_airlight(const RenderOptions& o, const RenderScene& scene, const Mesh& volume,
                              Progress& progress, std::vector<double>* frame_seconds,
                              std::vector<double>* generation_seconds, std::string* renderer_name) {
  if (o.method == "reference") {
    progress.begin("rendering reference (CPU, double precision)");
    Image image = render_reference(volume, scene);
    progress.end();
    return image;
  }
#ifdef LIGHTVOL_WITH_GL
  Result<std::unique_ptr<gl::Context>> context = gl::Context::create();
  if (!context) return context.error();
  *renderer_name = (*context)->renderer();
  progress.begin("rendering " + o.method + " on " + (*context)->renderer());
  Image image;
  if (o.method == "volume") {
    GlVolumeOptions vo;
    vo.density.tile = o.grid_tile;
    vo.density.slices = o.grid_slices;
    vo.density.opacity.size = o.opacity_size;
    vo.density.opacity.layers = o.opacity_layers;
    Result<std::unique_ptr<GlVolumeRenderer>> renderer = GlVolumeRenderer::create(scene, vo);
    if (!renderer) return renderer.error();
    (*renderer)->set_volume(volume);
    image = render_frames(**renderer, o.frames, frame_seconds);
  } else if (o.method == "live") {
    // The shadow map goes to the GPU as a texture; each frame makes the volume from it there.
    Result<ShadowMaps> maps = read_shadow_maps(scene.light, o.shadow_maps, {o.channel});
    if (!maps) return maps.error();
    std::vector<gl::TextureHandle> textures;
    std::vector<GlShadowMap> on_gpu;
    for (const DepthImage& map : maps->images()) {
      textures.push_back(upload_shadow_map(scene.light, map));
      on_gpu.push_back({textures.back().id(), map.width, map.height});
    }
    LiveOptions live_options;
    if (o.adaptive) live_options.max_error = o.max_error;
    Result<std::unique_ptr<LiveVolume>> live =
        LiveVolume::create(scene.light, on_gpu, live_options);
    if (!live) return live.error();
    Result<std::unique_ptr<GlVolumeRenderer>> renderer = GlVolumeRenderer::create(scene);
    if (!renderer) return renderer.error();
    if (Status s = (*renderer)->set_volume(**live); !s) return s.error();
    image = render_frames(**renderer, o.frames, frame_seconds);
    for (int i = 0; i < o.frames; ++i) {
      const auto start = std::chrono::steady_clock::now();
      (*live)->generate();
      gl::glFinish();
      generation_seconds->push_back(
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
  } else {
    ShadowMaps maps;  // radial needs none
    if (!o.shadow_maps.empty()) {
      Result<ShadowMaps> read = read_shadow_maps(scene.light, o.shadow_maps, {o.channel});
      if (!read) return read.error();
      maps = std::move(*read);
    }
    MarchOptions mo;
    mo.samples = o.samples;
    mo.interleave = o.interleave;
    mo.method = o.method == "radial" ? MarchMethod::radial : MarchMethod::raymarch;
    mo.opacity.size = o.opacity_size;
    mo.opacity.layers = o.opacity_layers;
    Result<std::unique_ptr<GlMarcher>> marcher =
        o.shadow_maps.empty() ? GlMarcher::create(scene, {}, {}, mo)
                              : GlMarcher::create(scene, maps.images(), maps.sources(), mo);
    if (!marcher) return marcher.error();
    image = render_frames(**marcher, o.frames, frame_seconds);
  }
  progress.end();
  return image;
#else
  (void)scene, (void)volume, (void)frame_seconds, (void)generation_seconds, (void)renderer_name;
  return Error{"--method " + o.method +
               ": this lightvol was built without OpenGL (LIGHTVOL_WITH_GL=OFF)"};
#endif
}

int run_render(const RenderOptions& o) {
  Progress progress(o.quiet);
  if (const std::string conflict = conflicting_flags(o); !conflict.empty()) return fail(conflict);

  Result<RenderScene> scene = load_render_scene(o, progress);
  if (!scene) return fail(scene.error());
  Mesh volume;
  if (needs_mesh(o)) {
    progress.begin("reading " + o.mesh_path);
    Result<Mesh> mesh = read_mesh(o.mesh_path);
    if (!mesh) return fail(mesh.error());
    volume = std::move(*mesh);
    progress.end(thousands(volume.num_triangles()) + " triangles");
  }

  std::vector<double> frame_seconds, generation_seconds;
  std::string renderer_name;
  Result<Image> image = render_airlight(o, *scene, volume, progress, &frame_seconds,
                                        &generation_seconds, &renderer_name);
  if (!image) return fail(image.error());
  // Surfaces of constant radiance `background` seen through the medium.
  if (o.composite) add_constant_surfaces(*scene, o.background, &*image);

  progress.begin("writing " + o.out_path);
  if (Status s = write_image(o.out_path, *image, o.exposure); !s) return fail(s.error());
  progress.end();

  double sum = 0, peak = 0;
  for (double v : image->values) {
    sum += v;
    peak = std::max(peak, std::abs(v));
  }
  std::printf("%s: %dx%d airlight, method %s, mean %.6g, max %.6g\n", o.out_path.c_str(),
              image->width, image->height, o.method.c_str(),
              image->values.empty() ? 0.0 : sum / static_cast<double>(image->values.size()), peak);
  if (!frame_seconds.empty())
    std::printf("time per frame: %.3f ms (median of %zu frames, %s)\n", 1e3 * median(frame_seconds),
                frame_seconds.size(), renderer_name.c_str());
  if (!generation_seconds.empty())
    std::printf("volume generation alone: %.3f ms (median of %zu)\n",
                1e3 * median(generation_seconds), generation_seconds.size());
  if (o.compare_path.empty()) return 0;
  Result<Image> ref = read_image(o.compare_path);
  if (!ref) return fail(ref.error());
  if (ref->width != image->width || ref->height != image->height)
    return fail(o.compare_path + ": image is " + size_text(ref->width, ref->height) +
                ", the render is " + size_text(image->width, image->height));
  const ImageDifference d = compare_images(*image, *ref);
  std::printf("compared with %s: relative L2 %.3e, max abs error %.3e, PSNR %.2f dB\n",
              o.compare_path.c_str(), d.relative_l2, d.max_abs, d.psnr_db);
  return 0;
}

}  // namespace

void add_render_command(CLI::App& app, Runner* run) {
  auto o = std::make_shared<RenderOptions>();
  CLI::App* cmd = app.add_subcommand(
      "render",
      "Render the airlight a light volume adds to a camera's picture (OpenGL), or a reference.");
  cmd->footer(
      "Example:\n  lightvol render volume.ply --light light.json --camera cam.json --depth "
      "camdepth.exr \\\n      --medium medium.json --out airlight.png\n"
      "Methods: volume (the light volume drawn with signed additive blending, OpenGL), live (the\n"
      "same, its volume made on the GPU each frame from --shadow-map; no MESH), reference (the\n"
      "exact sum on the CPU, double precision), raymarch (steps through the shadow map,\n"
      "--shadow-map) and radial (a radial blur of the camera depth), the last two for comparison.\n"
      ".exr output keeps linear floats; .png is tone-mapped. Exit 2 on bad input.");
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
  cmd->add_option("--method", o->method, "volume | live | reference | raymarch | radial")
      ->check(CLI::IsMember({"volume", "live", "reference", "raymarch", "radial"}))
      ->capture_default_str();
  cmd->add_option(
      "--shadow-map", o->shadow_maps,
      "live, raymarch: the light's shadow map (omni: six faces, a {face} path or a W x 6W strip)");
  cmd->add_flag("--adaptive", o->adaptive,
                "live: the adaptive volume (build --adaptive --tessellation quadtree's quadtree), "
                "made by compute shaders each frame; spot, directional and omni lights");
  cmd->add_option("--max-error", o->max_error,
                  "Error bound of --adaptive, in world units along each texel ray")
      ->check(decimal_number())
      ->check(CLI::Range(0.0, 1e300));
  cmd->add_option("--channel", o->channel, "Channel of the depth images (EXR Z, R, ...)");
  cmd->add_option("--samples", o->samples, "raymarch: steps per pixel; radial: blur samples")
      ->check(decimal_integer())
      ->capture_default_str();
  cmd->add_option("--interleave", o->interleave, "raymarch: M for M x M interleaved sampling")
      ->check(decimal_integer())
      ->capture_default_str();
  cmd->add_flag("--composite", o->composite,
                "Add surfaces of radiance --background seen through the medium");
  cmd->add_option("--background", o->background, "Surface radiance for --composite")
      ->check(decimal_number())
      ->capture_default_str();
  cmd->add_option("--exposure", o->exposure, "PNG: scale before tone mapping (default: automatic)")
      ->check(decimal_number());
  cmd->add_option("--compare", o->compare_path,
                  "Print relative L2, max abs error and PSNR against this .exr");
  cmd->add_option("--frames", o->frames,
                  "Render K more frames and print the median GPU time per frame (live: and of "
                  "the volume's generation alone)")
      ->check(decimal_integer());
  cmd->add_option("--grid-tile", o->grid_tile,
                  "density, volume: pixels per in-scattering column side (0: automatic)")
      ->capture_default_str()
      ->check(decimal_integer());
  cmd->add_option("--grid-slices", o->grid_slices,
                  "density, volume: samples along each in-scattering column")
      ->capture_default_str()
      ->check(decimal_integer());
  cmd->add_option("--opacity-size", o->opacity_size,
                  "density, volume and raymarch: opacity map columns per side (per face)")
      ->capture_default_str()
      ->check(decimal_integer());
  cmd->add_option("--opacity-layers", o->opacity_layers,
                  "density, volume and raymarch: opacity map layers along the light's depth")
      ->capture_default_str()
      ->check(decimal_integer());
  cmd->add_flag("--quiet", o->quiet, "No progress lines");
  cmd->callback([o, run] { *run = [o] { return run_render(*o); }; });
}

}  // namespace lightvol::cli
