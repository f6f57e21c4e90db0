#include "support/analytic_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <gtest/gtest.h>

#include "support/test_support.h"

namespace lightvol::test {

double cast_scene(Vec3d o, Vec3d d, const Box& box) {
  double best = std::numeric_limits<double>::infinity();
  if (d.y != 0) {
    const double t = -o.y / d.y;
    if (t > 0) best = t;
  }
  // Slab test for the box.
  double t0 = 0, t1 = std::numeric_limits<double>::infinity();
  for (int c = 0; c < 3; ++c) {
    const double oc = o[c], dc = d[c], lo = box.lo[c], hi = box.hi[c];
    if (dc == 0) {
      if (oc < lo || oc > hi) return best;
      continue;
    }
    double a = (lo - oc) / dc, b = (hi - oc) / dc;
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
  }
  if (t0 <= t1 && t0 > 0) best = std::min(best, t0);
  return best;
}

DepthImage scene_shadow_map(const Light& light, int width, int height, const Box& box, int face) {
  EXPECT_EQ(light.depth, DepthEncoding::linear);
  const Unprojector un(light, width, height, face, Space::world);
  const Mat4d view = light.type == LightType::omni ? omni_face_view(light, face) : light.view;
  DepthImage image;
  image.width = width;
  image.height = height;
  image.values.resize(static_cast<std::size_t>(width) * height);
  for (int row = 0; row < height; ++row)
    for (int col = 0; col < width; ++col) {
      const Vec3d a = un.near_point(col, row), b = un.far_point(col, row);
      const Vec3d dir = normalize(b - a);
      const Vec3d origin = light.is_perspective() ? light.position : a;
      const double t = cast_scene(origin, dir, box);
      double depth = light.far;
      if (std::isfinite(t)) depth = -view.transform_point(origin + t * dir).z;
      image.values[static_cast<std::size_t>(row) * width + col] =
          static_cast<float>(std::clamp(depth, light.near, light.far));
    }
  return image;
}

CubeFaces scene_cube_faces(const Light& light, int size, const Box& box) {
  CubeFaces cube;
  for (int f = 0; f < kOmniFaces; ++f) {
    cube.faces[f] = scene_shadow_map(light, size, size, box, f);
    cube.sources[f] = omni_face_name(f);
  }
  return cube;
}

bool scene_lit(const Light& light, int width, int height, Vec3d x, const Box& box) {
  const Vec3d eye = light.view.transform_point(x);
  if (-eye.z < light.near || -eye.z > light.far) return false;
  const Vec3d ndc = light.projection.transform_point(eye);
  if (std::abs(ndc.x) > 1.0 - 1.0 / width || std::abs(ndc.y) > 1.0 - 1.0 / height) return false;
  Vec3d origin = light.position, dir;
  double dist = 0;
  if (light.is_perspective()) {
    dist = length(x - origin);
    dir = (1.0 / dist) * (x - origin);
  } else {
    dir = light.direction;
    dist = dot(x - light.position, dir);
    origin = x - dist * dir;
  }
  return cast_scene(origin, dir, box) >= dist * (1 - 1e-12);
}

Camera make_camera(Vec3d position, Vec3d target, int width, int height, double fov_y_deg) {
  Camera camera;
  camera.width = width;
  camera.height = height;
  Light& v = camera.view;
  v.type = LightType::spot;
  v.depth = DepthEncoding::linear;
  v.near = 0.05;
  v.far = 100;
  v.position = position;
  v.direction = normalize(target - position);
  v.view = look_at(position, v.direction, {0, 1, 0});
  v.projection = perspective(fov_y_deg, double(width) / height, v.near, v.far);
  return camera;
}

RenderScene make_render_scene(const Camera& camera, const Light& light, const Medium& medium,
                              const Box& box) {
  RenderScene scene;
  scene.camera = camera;
  scene.light = light;
  scene.medium = medium;
  scene.surface.resize(static_cast<std::size_t>(camera.width) * camera.height);
  for (int row = 0; row < camera.height; ++row)
    for (int col = 0; col < camera.width; ++col) {
      const Ray ray = pixel_ray(camera, col, row);
      scene.surface[static_cast<std::size_t>(row) * camera.width + col] =
          cast_scene(ray.origin, ray.direction, box);
    }
  return scene;
}

double brute_force_airlight(const RenderScene& scene, int width, int height, int col, int row,
                            int steps, double max_t, const Box& box) {
  const Ray ray = pixel_ray(scene.camera, col, row);
  const double end =
      std::min(max_t, scene.surface[static_cast<std::size_t>(row) * scene.camera.width + col]);
  const Medium& m = scene.medium;
  const double st = m.extinction();
  const double ds = end / steps;
  const bool varying = m.density.varying();
  // Midpoint sums of ρ: the eye-side optical depth as the march goes, the light side per sample.
  const auto optical_depth = [&](Vec3d from, Vec3d to) {
    if (!varying) return st * length(to - from);
    constexpr int kLightSteps = 200;
    double sum = 0;
    for (int k = 0; k < kLightSteps; ++k)
      sum += m.density(from + ((k + 0.5) / kLightSteps) * (to - from));
    return st * sum * length(to - from) / kLightSteps;
  };
  double sum = 0, tau_eye = 0;
  for (int i = 0; i < steps; ++i) {
    const double s = (i + 0.5) * ds;
    const Vec3d x = ray.origin + s * ray.direction;
    const double rho = varying ? m.density(x) : 1.0;
    const double tau_here = varying ? tau_eye + 0.5 * st * rho * ds : st * s;
    tau_eye += st * rho * ds;
    if (!scene_lit(scene.light, width, height, x, box)) continue;
    double radiance = 0;
    if (scene.light.is_perspective()) {
      const Vec3d to_x = x - scene.light.position;
      const double d = length(to_x);
      const double cos_theta = dot((1.0 / d) * to_x, -1.0 * ray.direction);
      radiance = m.intensity * std::exp(-optical_depth(scene.light.position, x)) / (d * d) *
                 m.phase(cos_theta) * m.profile(dot(to_x, scene.light.direction) / d);
    } else {
      const double z = dot(x - scene.light.position, scene.light.direction) - scene.light.near;
      radiance = m.intensity * std::exp(-optical_depth(x - z * scene.light.direction, x)) *
                 m.phase(dot(scene.light.direction, -1.0 * ray.direction));
    }
    sum += m.scattering * rho * radiance * std::exp(-tau_here) * ds;
  }
  return sum;
}

Medium render_test_medium(double g) {
  Medium m;
  m.scattering = 0.06;
  m.absorption = 0.02;
  m.intensity = 20;
  m.phase = {PhaseType::hg, g, 0};
  return m;
}

std::vector<LightViewCase> light_view_cases() {
  return {
      {"spot window outside", spot_json("linear"), DepthEncoding::window, {6, 3, 6}, {0, 1, 0}},
      {"spot linear inside",
       spot_json("linear"),
       DepthEncoding::linear,
       {1.5, 0.6, 1.5},
       {-1, 0.3, -1}},
      {"directional window outside",
       directional_json("linear"),
       DepthEncoding::window,
       {7, 4, 5},
       {0, 0.5, 0}},
      {"directional linear inside",
       directional_json("linear"),
       DepthEncoding::linear,
       {2, 1, 2},
       {-1, 0.5, -2}},
  };
}

}  // namespace lightvol::test
