#include <algorithm>
#include <cmath>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <lightvol/airlight/heterogeneous.h>
#include <lightvol/core/check.h>
#include <lightvol/render/reference.h>
#include <lightvol/scene/bvh.h>

namespace lightvol {

ImageDifference compare_images(const Image& image, const Image& reference) {
  LV_CHECK_EQ(image.values.size(), reference.values.size());
  double diff2 = 0, ref2 = 0, peak = 0, max_abs = 0;
  for (std::size_t i = 0; i < image.values.size(); ++i) {
    const double d = image.values[i] - reference.values[i];
    diff2 += d * d;
    ref2 += reference.values[i] * reference.values[i];
    peak = std::max(peak, std::abs(reference.values[i]));
    max_abs = std::max(max_abs, std::abs(d));
  }
  ImageDifference out;
  out.relative_l2 = ref2 > 0 ? std::sqrt(diff2 / ref2) : std::sqrt(diff2);
  out.max_abs = max_abs;
  const double rmse =
      image.values.empty() ? 0 : std::sqrt(diff2 / static_cast<double>(image.values.size()));
  out.psnr_db = rmse > 0 ? 20.0 * std::log10(peak / rmse) : std::numeric_limits<double>::infinity();
  return out;
}

Image render_reference(const Mesh& volume, const RenderScene& scene, int stride) {
  LV_CHECK(stride >= 1);
  const Camera& cam = scene.camera;
  LV_CHECK_EQ(scene.surface.size(),
              static_cast<std::size_t>(cam.width) * static_cast<std::size_t>(cam.height));
  Image image;
  image.width = cam.width;
  image.height = cam.height;
  image.values.assign(scene.surface.size(), 0.0);
  const Bvh bvh(volume);
  const bool varying = scene.medium.density.varying();
  const double step = varying ? reference_step(scene.medium) : 0;
  tbb::parallel_for(
      tbb::blocked_range<int>(0, cam.height), [&](const tbb::blocked_range<int>& rows) {
        std::vector<RayHit> hits;
        for (int row = rows.begin(); row < rows.end(); ++row) {
          if (row % stride != stride / 2) continue;
          for (int col = stride / 2; col < cam.width; col += stride) {
            const std::size_t i = static_cast<std::size_t>(row) * cam.width + col;
            const Ray ray = pixel_ray(cam, col, row);
            hits.clear();
            bvh.intersect_all(ray.origin, ray.direction, 0.0, &hits);
            dedupe_hits(&hits);
            if (hits.empty()) continue;
            const double surface = scene.surface[i];
            if (varying) {
              // The lit intervals, then quadrature along them (heterogeneous.h).
              std::vector<std::pair<double, double>> crossings;
              for (const RayHit& h : hits)
                crossings.emplace_back(std::min(h.t, surface), h.facing > 0 ? 1.0 : -1.0);
              image.values[i] = heterogeneous_airlight(scene.light, scene.medium, ray,
                                                       lit_intervals(crossings), step);
              continue;
            }
            const RayAirlight la(scene.light, scene.medium, ray);
            double sum = 0;
            // Hits beyond the surface all clamp to it and share one value.
            double at_surface = std::numeric_limits<double>::quiet_NaN();
            for (const RayHit& h : hits) {
              const double sign = h.facing > 0 ? 1.0 : -1.0;
              if (h.t >= surface) {
                if (std::isnan(at_surface)) at_surface = la(surface);
                sum += sign * at_surface;
              } else {
                sum += sign * la(h.t);
              }
            }
            image.values[i] = sum;
          }
        }
      });
  return image;
}

}  // namespace lightvol
