#include <algorithm>
#include <cstddef>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <lightvol/core/check.h>
#include <lightvol/scene/raycast.h>
#include <lightvol/scene/scene.h>

namespace lightvol {
namespace {

// Everything one pass needs to cast rays: clip → world for the ray ends, world → clip for depth.
struct PassRays {
  Mat4d clip_to_world;
  Mat4d world_to_clip;
  int width, height;
  bool flip_y;

  PassRays(const Light& light, int w, int h, int face) : width(w), height(h), flip_y(light.flip_y) {
    world_to_clip = light.projection * pass_view(light, face);
    bool ok = false;
    clip_to_world = inverse(world_to_clip, &ok);
    LV_CHECK(ok);
  }

  double cast(const Bvh& bvh, double x, double y, std::vector<RayHit>* hits) const {
    const double x_ndc = 2.0 * x / width - 1.0;
    const double y_down = 2.0 * y / height - 1.0;
    const double y_ndc = flip_y ? y_down : -y_down;
    const Vec3d near = clip_to_world.transform_point({x_ndc, y_ndc, -1});
    const Vec3d far = clip_to_world.transform_point({x_ndc, y_ndc, 1});
    const double span = length(far - near);
    const Vec3d dir = (1.0 / span) * (far - near);
    hits->clear();
    // Hits exactly on the near plane (t = 0) are clipped by OpenGL too.
    bvh.intersect_all(near, dir, 0.0, hits);
    double best = span;
    for (const RayHit& h : *hits)
      if (h.t < best) best = h.t;
    if (best >= span) return 1.0;
    const Vec3d ndc = world_to_clip.transform_point(near + best * dir);
    return std::clamp(0.5 * ndc.z + 0.5, 0.0, 1.0);
  }
};

}  // namespace

std::vector<double> raycast_window_depth(const Bvh& bvh, const Light& light, int width, int height,
                                         int face) {
  LV_CHECK(width > 0 && height > 0);
  const PassRays rays(light, width, height, face);
  std::vector<double> depth(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& range) {
    std::vector<RayHit> hits;
    for (int row = range.begin(); row < range.end(); ++row)
      for (int col = 0; col < width; ++col)
        depth[static_cast<std::size_t>(row) * width + col] =
            rays.cast(bvh, col + 0.5, row + 0.5, &hits);
  });
  return depth;
}

double raycast_point(const Bvh& bvh, const Light& light, int width, int height, int face, double x,
                     double y) {
  const PassRays rays(light, width, height, face);
  std::vector<RayHit> hits;
  return rays.cast(bvh, x, y, &hits);
}

}  // namespace lightvol
