// lightvol demo: the whole pipeline on the bundled real scene (data/sponza_crop.ply, the middle of
// the Sponza atrium): shadow map → static and adaptive volumes → check → render, with pictures
// and a short printed summary.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <lightvol/airlight/airlight.h>
#include <lightvol/check/check.h>
#include <lightvol/core/atomic_file.h>
#include <lightvol/core/mesh.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/export/export.h>
#include <lightvol/light/light.h>
#include <lightvol/render/image_io.h>
#include <lightvol/render/scene.h>
#include <lightvol/scene/bvh.h>
#include <lightvol/scene/raycast.h>
#include <lightvol/scene/scene.h>
#include <lightvol/volume/adaptive_volume.h>
#include <lightvol/volume/static_volume.h>
#ifdef LIGHTVOL_HAS_SHADOWMAP
#include <lightvol/gl/context.h>
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

// One line of the printed summary.
struct Row {
  std::string step, file, count, result;
  double seconds = 0;
};

std::string size_text(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

// One exposure for every picture of the demo, so that they compare by eye: the static volume's
// 99.5th percentile of positive airlight maps to 1.5 (softer than write_image's default 4, which
// saturates the lit shafts).
double exposure_for(const Image& image) {
  std::vector<double> v;
  for (const double x : image.values)
    if (x > 0) v.push_back(x);
  if (v.empty()) return 1.0;
  const std::size_t k = std::min(v.size() - 1, v.size() * 995 / 1000);
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k] > 0 ? 1.5 / v[k] : 1.0;
}

// The demo's picture: the surfaces the camera sees, lit by the spot light (Lambert, albedo 0.35,
// shadowed by the shadow map, plus a little ambient light), seen through the medium, plus the
// airlight of the volume. Normals come from the camera depth (neighbouring pixels' points).
Image lit_surfaces(const RenderScene& scene, const std::vector<float>& shadow_window, int sw,
                   int sh, const Image& airlight) {
  const Camera& cam = scene.camera;
  const Light& light = scene.light;
  const Mat4d to_clip = light.projection * light.view;
  bool ok = false;
  const Mat4d inv_projection = inverse(light.projection, &ok);
  const auto eye_depth = [&](double d) {
    return -inv_projection.transform_point({0, 0, 2 * d - 1}).z;
  };
  const double st = scene.medium.extinction();
  const int w = cam.width, h = cam.height;
  std::vector<Vec3d> points(static_cast<std::size_t>(w) * h);
  std::vector<bool> hit(points.size());
  for (int row = 0; row < h; ++row)
    for (int col = 0; col < w; ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * w + col;
      const Ray ray = pixel_ray(cam, col, row);
      hit[i] = std::isfinite(scene.surface[i]);
      if (hit[i]) points[i] = ray.origin + scene.surface[i] * ray.direction;
    }
  Image image = airlight;
  for (int row = 0; row < h; ++row)
    for (int col = 0; col < w; ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * w + col;
      if (!hit[i]) continue;
      const Vec3d p = points[i];
      // Tangents toward the neighbour nearer in depth on each axis.
      const auto tangent = [&](int dc, int dr) {
        Vec3d best{0, 0, 0};
        double best_len = 1e300;
        for (const int s : {-1, 1}) {
          const int c = col + s * dc, r = row + s * dr;
          if (c < 0 || r < 0 || c >= w || r >= h) continue;
          const std::size_t j = static_cast<std::size_t>(r) * w + c;
          if (!hit[j]) continue;
          const Vec3d t = s * (points[j] - p);
          if (length(t) < best_len) best_len = length(t), best = t;
        }
        return best;
      };
      Vec3d n = cross(tangent(1, 0), tangent(0, 1));
      if (length(n) == 0) continue;
      n = normalize(n);
      const Ray ray = pixel_ray(cam, col, row);
      if (dot(n, ray.direction) > 0) n = -1.0 * n;
      const Vec3d to_light = light.position - p;
      const double dist = length(to_light);
      double lit = 0;
      const Vec3d ndc = to_clip.transform_point(p);
      if (std::abs(ndc.x) < 1 && std::abs(ndc.y) < 1 && ndc.z < 1) {
        const int sc = std::min(sw - 1, static_cast<int>((ndc.x + 1) * 0.5 * sw));
        const int sr = std::min(sh - 1, static_cast<int>((1 - ndc.y) * 0.5 * sh));
        const double stored = shadow_window[static_cast<std::size_t>(sr) * sw + sc];
        const double here = eye_depth(0.5 * ndc.z + 0.5);
        if (here <= eye_depth(stored) * 1.01 + 0.02) lit = 1;
      }
      const double cos_l = std::max(0.0, dot(n, (1.0 / dist) * to_light));
      const double irradiance =
          lit * scene.medium.intensity * cos_l / (dist * dist) * std::exp(-st * dist);
      const double radiance = 0.35 / 3.14159265358979 * irradiance + 0.003;
      image.values[i] += radiance * std::exp(-st * scene.surface[i]);
    }
  return image;
}

std::string check_text(const CheckReport& report) {
  if (!report.valid()) return "INVALID: " + report.first_failure();
  return "valid (" + std::string(to_string(report.proof)) + ")";
}

// Window-depth passes of a view: OpenGL when a context exists, else CPU ray casting.
class DepthPasses {
 public:
  explicit DepthPasses(const Mesh& scene) : scene_(scene) {
#ifdef LIGHTVOL_HAS_SHADOWMAP
    Result<std::unique_ptr<gl::Context>> context = gl::Context::create();
    if (context) {
      Result<ShadowMapRenderer> renderer = ShadowMapRenderer::create(scene);
      if (renderer) {
        context_ = std::move(*context);
        renderer_ = std::make_unique<ShadowMapRenderer>(std::move(*renderer));
        return;
      }
      why_ = renderer.error().message;
    } else {
      why_ = context.error().message;
    }
#else
    why_ = "built without OpenGL (LIGHTVOL_WITH_GL=OFF)";
#endif
  }

  bool gl() const {
#ifdef LIGHTVOL_HAS_SHADOWMAP
    return renderer_ != nullptr;
#else
    return false;
#endif
  }
  const std::string& why_not_gl() const { return why_; }

  Result<std::vector<float>> window(const Light& view, int w, int h) {
#ifdef LIGHTVOL_HAS_SHADOWMAP
    if (renderer_) return renderer_->render_window_depth(view, w, h, 0);
#endif
    if (!bvh_) bvh_ = std::make_unique<Bvh>(scene_);
    const std::vector<double> d = raycast_window_depth(*bvh_, view, w, h, 0);
    return std::vector<float>(d.begin(), d.end());
  }

 private:
  const Mesh& scene_;
  std::unique_ptr<Bvh> bvh_;
  std::string why_;
#ifdef LIGHTVOL_HAS_SHADOWMAP
  std::unique_ptr<gl::Context> context_;
  std::unique_ptr<ShadowMapRenderer> renderer_;
#endif
};

// What the web viewer (web/) needs beside the demo's other outputs: the volumes as GLBs carrying
// their light and the medium, the scene as a GLB, the camera (at the demo's image size) and the
// medium.
Status write_viewer_inputs(const std::string& data, const std::string& dir, const Mesh& scene,
                           const Light& light, const Camera& camera,
                           const std::vector<std::pair<std::string, const Mesh*>>& volumes) {
  const auto slurp = [](const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  const std::string medium_text = slurp(data + "/sponza_medium.json");
  nlohmann::json camera_json =
      nlohmann::json::parse(slurp(data + "/sponza_camera.json"), nullptr, false);
  if (camera_json.is_discarded()) return Error{data + "/sponza_camera.json: not JSON"};
  camera_json["width"] = camera.width;
  camera_json["height"] = camera.height;
  ExportOptions options;
  options.glb.light = &light;
  options.glb.medium_json = nlohmann::json::parse(medium_text, nullptr, false).dump();
  for (const auto& [name, mesh] : volumes)
    if (Status s = write_mesh(dir + "/volume_" + name + ".glb", *mesh, options); !s) return s;
  if (Status s = write_mesh(dir + "/scene.glb", scene); !s) return s;
  if (Status s = write_bytes_atomically(dir + "/camera.json", camera_json.dump(2) + "\n"); !s)
    return s;
  return write_bytes_atomically(dir + "/medium.json", medium_text);
}

int run_demo(const DemoOptions& o) {
  const std::string data = find_data_dir(o.data_dir);
  std::error_code ec;
  fs::create_directories(o.out_dir, ec);
  if (!fs::is_directory(o.out_dir)) return fail(o.out_dir + ": cannot create the output directory");
  const auto out = [&](const std::string& name) { return o.out_dir + "/" + name; };

  Progress progress(o.quiet);
  std::vector<Row> rows;
  const auto add_row = [&](const std::string& step, const std::string& file,
                           const std::string& count, const std::string& result) {
    progress.end();
    rows.push_back({step, file, count, result, progress.log().stages().back().seconds});
  };

  // ---- inputs -----------------------------------------------------------------------------------
  const std::string scene_path = data + "/sponza_crop.ply";
  progress.begin("reading " + scene_path);
  const Result<Mesh> scene = load_scene(scene_path);
  if (!scene) return fail(scene.error().message + " (is --data the bundled data/ folder?)");
  const Result<Light> light = load_light(data + "/sponza_spot.json");
  if (!light) return fail(light.error().message);
  Result<Camera> camera = load_camera(data + "/sponza_camera.json");
  if (!camera) return fail(camera.error().message);
  const Result<Medium> medium = load_medium(data + "/sponza_medium.json");
  if (!medium) return fail(medium.error().message);
  // Smaller shadow maps (tests) get a proportionally smaller camera image.
  if (o.size < 512) {
    camera->width = std::max(16, camera->width * o.size / 512);
    camera->height = std::max(16, camera->height * o.size / 512);
  }
  progress.end();

  // ---- depth passes -----------------------------------------------------------------------------
  DepthPasses passes(*scene);
  const Result<MapSize> size = shadow_map_size(*light, o.size, data + "/sponza_spot.json");
  if (!size) return fail(size.error().message);
  progress.begin("shadow map");
  Result<std::vector<float>> shadow_window = passes.window(*light, size->width, size->height);
  if (!shadow_window) return fail(shadow_window.error().message);
  const DepthImage shadow = encode_depth(*light, size->width, size->height, *shadow_window);
  if (Status s = write_depth_image(out("shadow_map.exr"), shadow); !s)
    return fail(s.error().message);
  if (Status s =
          write_depth_image(out("shadow_map.png"),
                            depth_preview(*light, size->width, size->height, {*shadow_window}));
      !s)
    return fail(s.error().message);
  add_row("shadow map " + size_text(size->width, size->height), "shadow_map.exr",
          thousands(scene->num_triangles()) + " scene",
          passes.gl() ? "OpenGL" : "CPU ray casting (" + passes.why_not_gl() + ")");

  progress.begin("camera depth");
  Result<std::vector<float>> camera_window =
      passes.window(camera->view, camera->width, camera->height);
  if (!camera_window) return fail(camera_window.error().message);
  const DepthImage camera_depth =
      encode_depth(camera->view, camera->width, camera->height, *camera_window);
  if (Status s = write_depth_image(out("camera_depth.exr"), camera_depth); !s)
    return fail(s.error().message);
  if (Status s = write_depth_image(
          out("camera_depth.png"),
          depth_preview(camera->view, camera->width, camera->height, {*camera_window}));
      !s)
    return fail(s.error().message);
  add_row("camera depth " + size_text(camera->width, camera->height), "camera_depth.exr", "", "");

  // ---- volumes ----------------------------------------------------------------------------------
  struct Volume {
    std::string name;
    Mesh mesh;
  };
  std::vector<Volume> volumes;
  progress.begin("static volume");
  Result<Mesh> fixed = build_static_volume(*light, shadow, {}, "shadow_map.exr");
  if (!fixed) return fail(fixed.error().message);
  if (Status s = write_mesh(out("volume_static.ply"), *fixed); !s) return fail(s.error().message);
  add_row("static volume", "volume_static.ply", thousands(fixed->num_triangles()) + " tris", "");
  volumes.push_back({"static", std::move(*fixed)});

  progress.begin("adaptive volume");
  AdaptiveOptions adaptive;
  adaptive.max_error = o.max_error;
  Result<Mesh> coarse = build_adaptive_volume(*light, shadow, {}, adaptive, "shadow_map.exr");
  if (!coarse) return fail(coarse.error().message);
  if (Status s = write_mesh(out("volume_adaptive.ply"), *coarse); !s)
    return fail(s.error().message);
  char error_text[64];
  std::snprintf(error_text, sizeof error_text, "max error %g", o.max_error);
  add_row("adaptive volume", "volume_adaptive.ply", thousands(coarse->num_triangles()) + " tris",
          error_text);
  volumes.push_back({"adaptive", std::move(*coarse)});

  progress.begin("web viewer inputs");
  if (Status st = write_viewer_inputs(
          data, o.out_dir, *scene, *light, *camera,
          {{volumes[0].name, &volumes[0].mesh}, {volumes[1].name, &volumes[1].mesh}});
      !st)
    return fail(st.error().message);
  add_row("web viewer inputs", "volume_static.glb", "", "+ adaptive, scene, camera, medium");

  bool all_valid = true;
  for (const Volume& v : volumes) {
    progress.begin("check " + v.name);
    const CheckReport report = check_volume_linear(v.mesh, &*light);
    all_valid = all_valid && report.valid();
    add_row("check " + v.name, "", "", check_text(report));
  }

  // ---- rendering ------------------------------------------------------------------------------
#ifdef LIGHTVOL_HAS_SHADOWMAP
  if (passes.gl()) {
    RenderScene render_scene;
    render_scene.camera = *camera;
    render_scene.light = *light;
    render_scene.medium = *medium;
    Result<std::vector<double>> surface = surface_distances(
        *camera, camera_depth.values, camera_depth.width, camera_depth.height, "camera_depth.exr");
    if (!surface) return fail(surface.error().message);
    render_scene.surface = std::move(*surface);

    std::vector<Image> images;
    Result<std::unique_ptr<GlVolumeRenderer>> volume_renderer =
        GlVolumeRenderer::create(render_scene);
    if (!volume_renderer) return fail(volume_renderer.error().message);
    for (const Volume& v : volumes) {
      progress.begin("render " + v.name + " volume");
      (*volume_renderer)->set_volume(v.mesh);
      double seconds = 0;
      images.push_back((*volume_renderer)->render(&seconds));
      const std::string name = "airlight_" + v.name;
      if (Status s = write_image(out(name + ".exr"), images.back()); !s)
        return fail(s.error().message);
      // One exposure for all pictures (the static volume's), so that they compare by eye.
      if (Status s = write_image(out(name + ".png"), images.back(), exposure_for(images[0])); !s)
        return fail(s.error().message);
      char text[96];
      std::snprintf(text, sizeof text, "GPU %.1f ms", seconds * 1e3);
      std::string result = text;
      if (images.size() > 1) {
        const ImageDifference d = compare_images(images.back(), images[0]);
        std::snprintf(text, sizeof text, "; vs static: rel. L2 %.2e", d.relative_l2);
        result += text;
      }
      add_row("render " + v.name + " (volume)", name + ".png",
              size_text(camera->width, camera->height), result);
    }
    MarchOptions march;
    march.samples = 128;
    march.interleave = 2;
    Result<std::unique_ptr<GlMarcher>> marcher =
        GlMarcher::create(render_scene, {shadow}, {"shadow_map.exr"}, march);
    if (!marcher) return fail(marcher.error().message);
    progress.begin("render raymarch");
    double seconds = 0;
    const Image marched = (*marcher)->render(&seconds);
    if (Status s = write_image(out("airlight_raymarch.exr"), marched); !s)
      return fail(s.error().message);
    if (Status s = write_image(out("airlight_raymarch.png"), marched, exposure_for(images[0])); !s)
      return fail(s.error().message);
    char text[96];
    std::snprintf(text, sizeof text, "GPU %.1f ms; vs static: rel. L2 %.2e", seconds * 1e3,
                  compare_images(marched, images[0]).relative_l2);
    add_row("render raymarch 128x2x2", "airlight_raymarch.png",
            size_text(camera->width, camera->height), text);

    progress.begin("composite");
    const Image picture =
        lit_surfaces(render_scene, *shadow_window, size->width, size->height, images[0]);
    if (Status s = write_image(out("demo.png"), picture, exposure_for(picture)); !s)
      return fail(s.error().message);
    add_row("picture", "demo.png", size_text(camera->width, camera->height),
            "lit surfaces + static volume's airlight");
  } else {
    rows.push_back({"render", "", "", "skipped: no OpenGL (" + passes.why_not_gl() + ")", 0});
  }
#else
  rows.push_back({"render", "", "", "skipped: built without OpenGL", 0});
#endif

  // ---- summary ----------------------------------------------------------------------------------
  if (!o.quiet) {
    std::printf("%-26s %-22s %-18s %8s  %s\n", "step", "output", "size", "time", "result");
    for (const Row& r : rows)
      std::printf("%-26s %-22s %-18s %7.2fs  %s\n", r.step.c_str(), r.file.c_str(), r.count.c_str(),
                  r.seconds, r.result.c_str());
    std::printf(
        "outputs in %s/ (scene: Sponza atrium by Marko Dabrovic, the middle of the atrium)\n",
        o.out_dir.c_str());
  }
  const fs::path serve = fs::path(data).parent_path() / "web" / "serve.mjs";
  if (!o.quiet && fs::exists(serve))
    std::printf(
        "view it in a browser: node %s %s\n  then open "
        "http://127.0.0.1:8000/web/"
        "index.html?volume=/data/volume_static.glb&camera=/data/camera.json&medium=/data/"
        "medium.json&scene=/data/scene.glb\n",
        serve.string().c_str(), o.out_dir.c_str());
  if (!all_valid) return fail("a demo volume failed its checks (see the table)");
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
      ->check(CLI::Range(8, 4096))
      ->capture_default_str();
  cmd->add_option("--max-error", o->max_error, "Adaptive volume's error bound, world units")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--data", o->data_dir, "The bundled data folder (default: found automatically)");
  cmd->add_flag("--quiet,-q", o->quiet, "No progress lines and no summary");
  cmd->callback([o, run] { *run = [o] { return run_demo(*o); }; });
}

}  // namespace lightvol::cli
