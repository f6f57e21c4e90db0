// lightvol render: the OpenGL checker. Renders the signed single-scattering airlight of a light
// volume (or, for comparison, ray marching and radial blur from the shadow maps) from a camera.
// The steps are the library's (render/airlight_render.h, render/gl_airlight_render.h); here the
// flags, the volume's read and the printed lines.
#include <cstdio>
#include <string>
#include <vector>

#include <lightvol/core/mesh.h>
#include <lightvol/io/mesh_reader.h>
#include <lightvol/render/airlight_render.h>
#include <lightvol/render/image_io.h>
#include <lightvol/render/surfaces.h>
#ifdef LIGHTVOL_WITH_GL
#include <lightvol/render/gl_airlight_render.h>
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

// The library's request for the flags `o`.
RenderRequest render_request(const RenderOptions& o) {
  RenderRequest r;
  r.method = o.method == "live"        ? RenderMethod::live
             : o.method == "reference" ? RenderMethod::reference
             : o.method == "raymarch"  ? RenderMethod::raymarch
             : o.method == "radial"    ? RenderMethod::radial
                                       : RenderMethod::volume;
  r.camera_path = o.camera_path;
  r.light_path = o.light_path;
  r.medium_path = o.medium_path;
  r.depth_path = o.depth_path;
  r.channel = o.channel;
  r.shadow_map_paths = o.shadow_maps;
  r.samples = o.samples;
  r.interleave = o.interleave;
  if (o.adaptive) r.max_error = o.max_error;
  r.frames = o.frames;
  r.grid_tile = o.grid_tile;
  r.grid_slices = o.grid_slices;
  r.opacity_size = o.opacity_size;
  r.opacity_layers = o.opacity_layers;
  return r;
}

int run_render(const RenderOptions& o) {
  Progress progress(o.quiet);
  if (const std::string conflict = conflicting_flags(o); !conflict.empty()) return fail(conflict);
  const RenderRequest request = render_request(o);

  Result<RenderScene> scene = load_render_scene(request, progress.log());
  if (!scene) return fail(scene.error());
  Mesh volume;
  if (method_takes_mesh(request.method)) {
    progress.begin("reading " + o.mesh_path);
    Result<Mesh> mesh = read_mesh(o.mesh_path);
    if (!mesh) return fail(mesh.error());
    volume = std::move(*mesh);
    progress.end(thousands(volume.num_triangles()) + " triangles");
  }

#ifdef LIGHTVOL_WITH_GL
  Result<AirlightRender> render = render_airlight(request, *scene, volume, progress.log());
#else
  Result<AirlightRender> render =
      request.method == RenderMethod::reference
          ? render_airlight_reference(*scene, volume, progress.log())
          : Result<AirlightRender>(Error{"--method " + o.method +
                                         ": this lightvol was built without OpenGL "
                                         "(LIGHTVOL_WITH_GL=OFF)"});
#endif
  if (!render) return fail(render.error());
  Image& image = render->image;
  // Surfaces of constant radiance `background` seen through the medium.
  if (o.composite) add_constant_surfaces(*scene, o.background, &image);

  progress.begin("writing " + o.out_path);
  if (Status s = write_image(o.out_path, image, o.exposure); !s) return fail(s.error());
  progress.end();

  const ImageLevels levels = image_levels(image);
  std::printf("%s: %dx%d airlight, method %s, mean %.6g, max %.6g\n", o.out_path.c_str(),
              image.width, image.height, o.method.c_str(), levels.mean, levels.peak);
  if (!render->frame_seconds.empty())
    std::printf("time per frame: %.3f ms (median of %zu frames, %s)\n",
                1e3 * median(render->frame_seconds), render->frame_seconds.size(),
                render->renderer.c_str());
  if (!render->generation_seconds.empty())
    std::printf("volume generation alone: %.3f ms (median of %zu)\n",
                1e3 * median(render->generation_seconds), render->generation_seconds.size());
  if (o.compare_path.empty()) return 0;
  const Result<ImageDifference> d = compare_with_image_file(image, o.compare_path);
  if (!d) return fail(d.error());
  std::printf("compared with %s: relative L2 %.3e, max abs error %.3e, PSNR %.2f dB\n",
              o.compare_path.c_str(), d->relative_l2, d->max_abs, d->psnr_db);
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
