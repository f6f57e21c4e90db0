#include "support/omni_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <lightvol/core/check.h>
#include <lightvol/light/light.h>

namespace lightvol::test {
namespace {

constexpr double kNear = 0.05, kFar = 30;
const Vec3d kLight{0.3, 1.6, -0.4};

// Ray p + t·d against an axis-aligned box; the exit (inside == true) or entry distance, or ∞.
double box_hit(Vec3d p, Vec3d d, Vec3d lo, Vec3d hi, bool inside) {
  double t0 = -std::numeric_limits<double>::infinity(),
         t1 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0) {
      if (p[a] < lo[a] || p[a] > hi[a]) return std::numeric_limits<double>::infinity();
      continue;
    }
    double ta = (lo[a] - p[a]) / d[a], tb = (hi[a] - p[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  if (t0 > t1) return std::numeric_limits<double>::infinity();
  const double t = inside ? t1 : t0;
  return t > 0 ? t : std::numeric_limits<double>::infinity();
}

double sphere_hit(Vec3d p, Vec3d d, Vec3d c, double r) {
  const Vec3d o = p - c;
  const double b = dot(o, d), cc = dot(o, o) - r * r, disc = b * b - cc;
  if (disc < 0) return std::numeric_limits<double>::infinity();
  const double t = -b - std::sqrt(disc);
  return t > 0 ? t : std::numeric_limits<double>::infinity();
}

}  // namespace

std::string omni_scene_light_json() {
  return R"({"type": "omni", "position": [0.3, 1.6, -0.4], "near": 0.05, "far": 30, "depth": "window"})";
}

CubeFaces omni_scene(int width) {
  Result<Light> light = parse_light(omni_scene_light_json(), "omni_scene");
  LV_CHECK(light.ok());
  CubeFaces cube;
  for (int f = 0; f < kOmniFaces; ++f) {
    const Unprojector u(*light, width, width, f, Space::world);
    const Vec3d look = u.near_point(width / 2, width / 2) - kLight;  // ~ the face axis
    int axis = 0;
    for (int a = 1; a < 3; ++a)
      if (std::abs(look[a]) > std::abs(look[axis])) axis = a;
    DepthImage& face = cube.faces[f];
    face.width = face.height = width;
    face.values.resize(static_cast<std::size_t>(width) * width);
    for (int r = 0; r < width; ++r)
      for (int c = 0; c < width; ++c) {
        const Vec3d d = normalize(u.near_point(c, r) - kLight);
        // A room 10 × 4 × 8 with a window in the −Z wall (nothing hit), a pillar and a ball.
        double t = box_hit(kLight, d, {-5, 0, -4}, {5, 4, 4}, true);
        const Vec3d wall = kLight + t * d;
        if (wall.z < -3.999 && std::abs(wall.x - 1) < 1 && std::abs(wall.y - 2) < 0.8)
          t = std::numeric_limits<double>::infinity();
        t = std::min(t, box_hit(kLight, d, {-2.5, 0, 1}, {-1.9, 4, 1.6}, false));
        t = std::min(t, sphere_hit(kLight, d, {2, 1, 1.5}, 0.9));
        double value = 1;                        // nothing hit (or beyond far): the far plane
        const double z = t * std::abs(d[axis]);  // eye-space distance along the face's axis
        if (std::isfinite(t) && z < kFar) {
          const double z_ndc =
              (kFar + kNear) / (kFar - kNear) - 2 * kFar * kNear / ((kFar - kNear) * z);
          value = 0.5 * (z_ndc + 1);
        }
        face.values[static_cast<std::size_t>(r) * width + c] = static_cast<float>(value);
      }
    cube.sources[f] = "omni_scene";
  }
  return cube;
}

}  // namespace lightvol::test
