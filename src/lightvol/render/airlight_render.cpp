#include <algorithm>
#include <cmath>
#include <utility>

#include <lightvol/airlight/airlight.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/light/camera.h>
#include <lightvol/light/light.h>
#include <lightvol/render/airlight_render.h>
#include <lightvol/render/image_io.h>
#include <lightvol/render/reference.h>

namespace lightvol {
namespace {

std::string size_text(int width, int height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

}  // namespace

const char* to_string(RenderMethod method) {
  switch (method) {
    case RenderMethod::volume:
      return "volume";
    case RenderMethod::live:
      return "live";
    case RenderMethod::reference:
      return "reference";
    case RenderMethod::raymarch:
      return "raymarch";
    case RenderMethod::radial:
      return "radial";
  }
  return "?";
}

bool method_takes_mesh(RenderMethod method) {
  return method == RenderMethod::volume || method == RenderMethod::reference;
}

Result<RenderScene> load_render_scene(const RenderRequest& r, StageLog& log) {
  RenderScene scene;
  Result<Camera> camera = load_camera(r.camera_path);
  if (!camera) return camera.error();
  scene.camera = *camera;
  Result<Light> light = load_light(r.light_path);
  if (!light) return light.error();
  scene.light = *light;
  Result<Medium> medium = load_medium(r.medium_path);
  if (!medium) return medium.error();
  scene.medium = *medium;
  if (scene.medium.profile.enabled() && scene.light.type != LightType::spot)
    return Error{r.medium_path + ": key 'profile': applies to spot lights only, " + r.light_path +
                 " is a " + std::string(to_string(scene.light.type)) + " light"};
  if (scene.medium.density.varying() && r.method != RenderMethod::reference &&
      r.method != RenderMethod::volume && r.method != RenderMethod::raymarch)
    return Error{r.medium_path + ": key 'density': RenderRequest::method " + to_string(r.method) +
                 " renders homogeneous media only (volume, reference and raymarch take a density)"};
  log.begin("reading " + r.depth_path);
  Result<DepthImage> depth = read_depth_image(r.depth_path, {r.channel});
  if (!depth) return depth.error();
  Result<std::vector<double>> surface =
      surface_distances(scene.camera, depth->values, depth->width, depth->height, r.depth_path);
  if (!surface) return surface.error();
  scene.surface = std::move(*surface);
  log.end(size_text(depth->width, depth->height));
  return scene;
}

AirlightRender render_airlight_reference(const RenderScene& scene, const Mesh& volume,
                                         StageLog& log) {
  log.begin("rendering reference (CPU, double precision)");
  AirlightRender render;
  render.image = render_reference(volume, scene);
  log.end();
  return render;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty()
             ? 0
             : (v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]));
}

ImageLevels image_levels(const Image& image) {
  double sum = 0, peak = 0;
  for (double v : image.values) {
    sum += v;
    peak = std::max(peak, std::abs(v));
  }
  return {image.values.empty() ? 0.0 : sum / static_cast<double>(image.values.size()), peak};
}

Result<ImageDifference> compare_with_image_file(const Image& image, const std::string& path) {
  Result<Image> ref = read_image(path);
  if (!ref) return ref.error();
  if (ref->width != image.width || ref->height != image.height)
    return Error{path + ": image is " + size_text(ref->width, ref->height) + ", the render is " +
                 size_text(image.width, image.height)};
  return compare_images(image, *ref);
}

}  // namespace lightvol
