#include <algorithm>
#include <cmath>
#include <cstddef>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <lightvol/airlight/heterogeneous.h>
#include <lightvol/core/math.h>
#include <lightvol/render/surfaces.h>

namespace lightvol {

Image lit_surfaces(const RenderScene& scene, const std::vector<float>& shadow_window, int width,
                   int height, const Image& airlight, const SurfaceShading& shading) {
  const int sw = width, sh = height;
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
  // A varying density: each point's optical depths toward the light and the eye, else e^(−σt·d).
  std::vector<double> tau_light, tau_eye;
  if (scene.medium.density.varying()) {
    const double step = 2 * scene.medium.density.finest_wavelength();
    tau_light.assign(points.size(), 0.0);
    tau_eye.assign(points.size(), 0.0);
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, points.size()),
        [&](const tbb::blocked_range<std::size_t>& range) {
          for (std::size_t i = range.begin(); i < range.end(); ++i) {
            if (!hit[i]) continue;
            const Ray ray = pixel_ray(cam, static_cast<int>(i % w), static_cast<int>(i / w));
            if (shading.albedo != 0)  // else the light's side is not seen
              tau_light[i] = light_optical_depth(light, scene.medium, points[i], step);
            tau_eye[i] = segment_optical_depth(scene.medium, ray.origin, points[i], step);
          }
        });
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
      const double irradiance = lit * scene.medium.intensity * cos_l / (dist * dist) *
                                std::exp(tau_light.empty() ? -st * dist : -tau_light[i]);
      const double radiance = shading.albedo / 3.14159265358979 * irradiance + shading.ambient;
      image.values[i] +=
          radiance * std::exp(tau_eye.empty() ? -st * scene.surface[i] : -tau_eye[i]);
    }
  return image;
}

void add_constant_surfaces(const RenderScene& scene, double radiance, Image* image) {
  const double st = scene.medium.extinction();
  if (!scene.medium.density.varying()) {
    for (std::size_t i = 0; i < image->values.size(); ++i)
      image->values[i] += radiance * std::exp(-st * scene.surface[i]);
    return;
  }
  // A varying density: the eye-side optical depth σt ∫ρ along each pixel's ray to its surface,
  // with lit_surfaces' panels.
  const Camera& cam = scene.camera;
  const int w = cam.width;
  const double step = 2 * scene.medium.density.finest_wavelength();
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, image->values.size()),
      [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
          if (!std::isfinite(scene.surface[i])) continue;  // e^(−∞): nothing
          const Ray ray = pixel_ray(cam, static_cast<int>(i % w), static_cast<int>(i / w));
          const double tau = segment_optical_depth(
              scene.medium, ray.origin, ray.origin + scene.surface[i] * ray.direction, step);
          image->values[i] += radiance * std::exp(-tau);
        }
      });
}

double percentile_exposure(const Image& image, double target) {
  std::vector<double> v;
  for (const double x : image.values)
    if (x > 0) v.push_back(x);
  if (v.empty()) return 1.0;
  const std::size_t k = std::min(v.size() - 1, v.size() * 995 / 1000);
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k] > 0 ? target / v[k] : 1.0;
}

}  // namespace lightvol
