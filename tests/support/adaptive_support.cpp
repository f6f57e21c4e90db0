#include "support/adaptive_support.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/test_support.h"

namespace lightvol::test {

RayErrors ray_errors(const Mesh& mesh, const Light& light, const DepthImage& depth) {
  const int w = depth.width, h = depth.height;
  const Unprojector u(light, w, h, 0, Space::world);
  const std::size_t nv = mesh.num_vertices();
  std::vector<double> col(nv), row(nv);
  std::vector<bool> closing(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    const auto p = mesh.vertex(v);
    const Vec3d e = light.view.transform_point({p[0], p[1], p[2]});
    const Mat4d& pr = light.projection;
    const double cw = pr(3, 0) * e.x + pr(3, 1) * e.y + pr(3, 2) * e.z + pr(3, 3);
    if (std::abs(cw) < 1e-9) {
      closing[v] = true;
      continue;
    }
    const Vec3d n = pr.transform_point(e);
    closing[v] = n.z < -1 + 1e-4;
    col[v] = (n.x + 1) / 2 * w - 0.5;
    row[v] = (light.flip_y ? (n.y + 1) / 2 : (1 - n.y) / 2) * h - 0.5;
  }
  std::vector<double> best_t(static_cast<std::size_t>(w) * h, -1), err(best_t.size(), 0);
  for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
    const auto tri = mesh.triangle(t);
    if (closing[tri[0]] || closing[tri[1]] || closing[tri[2]]) continue;
    const double c0 = std::min({col[tri[0]], col[tri[1]], col[tri[2]]});
    const double c1 = std::max({col[tri[0]], col[tri[1]], col[tri[2]]});
    const double r0 = std::min({row[tri[0]], row[tri[1]], row[tri[2]]});
    const double r1 = std::max({row[tri[0]], row[tri[1]], row[tri[2]]});
    Vec3d p[3];
    for (int k = 0; k < 3; ++k) {
      const auto q = mesh.vertex(tri[k]);
      p[k] = {q[0], q[1], q[2]};
    }
    for (int r = std::max(0, int(std::ceil(r0 - 1e-3)));
         r <= std::min(h - 1, int(std::floor(r1 + 1e-3))); ++r)
      for (int c = std::max(0, int(std::ceil(c0 - 1e-3)));
           c <= std::min(w - 1, int(std::floor(c1 + 1e-3))); ++c) {
        const Vec3d o = u.near_point(c, r), dir = u.far_point(c, r) - o;
        const Vec3d e1 = p[1] - p[0], e2 = p[2] - p[0];
        const Vec3d pv = cross(dir, e2);
        const double det = dot(e1, pv);
        if (std::abs(det) < 1e-300) continue;
        const Vec3d tv = o - p[0];
        const double bu = dot(tv, pv) / det;
        const Vec3d qv = cross(tv, e1);
        const double bv = dot(dir, qv) / det;
        const double tol = 1e-4;  // float positions: border rays graze edges
        if (bu < -tol || bv < -tol || bu + bv > 1 + tol) continue;
        const double tt = dot(e2, qv) / det;
        const std::size_t k = static_cast<std::size_t>(r) * w + c;
        if (tt > best_t[k]) {
          best_t[k] = tt;
          Vec3d truth;
          u.point(c, r, depth.at(c, r), &truth);
          err[k] = length(o + tt * dir - truth);
        }
      }
  }
  RayErrors out;
  for (std::size_t k = 0; k < best_t.size(); ++k) {
    if (best_t[k] < 0) {
      if (out.missed < 5) ADD_FAILURE() << "missed texel " << k % w << ", " << k / w;
      ++out.missed;
    }
    out.max_error = std::max(out.max_error, err[k]);
  }
  return out;
}

// ---- maps --------------------------------------------------------------------------------------

DepthImage adaptive_scene(int w, int h, double floor_depth) {
  return make_depth(w, h, [=](int c, int r) {
    const double x = (c + 0.5) / w, y = (r + 0.5) / h;
    double d = floor_depth + 0.8 * x + 0.3 * y;                             // slope
    if (x > 0.1 && x < 0.3 && y > 0.15 && y < 0.45) d = floor_depth - 3;    // box
    if (x > 0.55 && x < 0.62 && y > 0.6 && y < 0.9) d = floor_depth - 2.2;  // box
    if (c == w / 2 || c == w / 2 + 3) d = floor_depth - 1.5;                // thin bars
    if (r == (2 * h) / 3) d = std::min(d, floor_depth - 1.0);               // thin bar
    const double dx = x - 0.75, dy = y - 0.3, rr = dx * dx + dy * dy;
    if (rr < 0.04) d = std::min(d, floor_depth - 4 + 10 * (0.2 - std::sqrt(0.04 - rr)));  // sphere
    return static_cast<float>(d);
  });
}

DepthImage window_scene(int w, int h) {
  return make_depth(w, h, [=](int c, int r) {
    const double x = (c + 0.5) / w, y = (r + 0.5) / h;
    double d = 0.95 + 0.02 * x;
    if (x > 0.2 && x < 0.5 && y > 0.2 && y < 0.35) d = 0.9;
    if (c == w / 3) d = 0.93;
    const double dx = x - 0.7, dy = y - 0.7, rr = dx * dx + dy * dy;
    if (rr < 0.02) d = 0.9 + 0.3 * rr;
    return static_cast<float>(d);
  });
}

void expect_valid_volume(const Mesh& mesh) {
  EXPECT_TRUE(test::is_closed_and_oriented(mesh));
  EXPECT_TRUE(test::has_no_degenerate_triangles(mesh));
  EXPECT_GT(signed_volume(mesh), 0);
}

namespace {
Vec3d vertex_of(const Mesh& mesh, std::uint32_t v) {
  const auto p = mesh.vertex(v);
  return {p[0], p[1], p[2]};
}
}  // namespace

double omni_ray_error(const Mesh& mesh, const Light& light, const CubeFaces& cube) {
  const int w = cube.size();
  double worst = 0;
  for (int f = 0; f < kOmniFaces; ++f) {
    const Unprojector u(light, w, w, f, Space::world);
    for (int r = 0; r < w; ++r)
      for (int c = 0; c < w; ++c) {
        Vec3d p;
        EXPECT_TRUE(u.point(c, r, cube.faces[f].at(c, r), &p));
        const Vec3d o = light.position, d = normalize(p - o);
        double hit = -1;
        for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
          const auto [i, j, k] = mesh.triangle(t);
          const Vec3d a = vertex_of(mesh, i), e1 = vertex_of(mesh, j) - a,
                      e2 = vertex_of(mesh, k) - a;
          const Vec3d pv = cross(d, e2);
          const double det = dot(e1, pv);
          if (det == 0) continue;
          const Vec3d tv = o - a;
          const double uu = dot(tv, pv) / det;
          if (uu < -1e-9 || uu > 1 + 1e-9) continue;
          const Vec3d qv = cross(tv, e1);
          const double vv = dot(d, qv) / det;
          if (vv < -1e-9 || uu + vv > 1 + 1e-9) continue;
          const double s = dot(e2, qv) / det;
          if (s > 0) hit = std::max(hit, s);
        }
        EXPECT_GT(hit, 0) << "face " << f << " texel " << c << "," << r << ": ray leaves nothing";
        worst = std::max(worst, std::abs(hit - length(p - o)));
      }
  }
  return worst;
}

std::string unit_box_json() {
  return R"({"type": "directional", "position": [0, 0, 0], "direction": [0, 0, -1], "up": [0, 1, 0],)"
         R"( "ortho": [-0.5, 0.5, -0.5, 0.5], "near": 0, "far": 1, "depth": "linear"})";
}

std::vector<LightRange> light_ranges() {
  return {{spot_json("window"), 0.96, 0.995},
          {spot_json("linear"), 2.0, 6.0},
          {directional_json("window"), 0.1, 0.6},
          {unit_box_json(), 0.05, 0.95}};
}

DepthImage plateau_scene(int w, int h, const LightRange& range, std::mt19937& rng, double jitter) {
  const double span = range.hi - range.lo;
  std::uniform_real_distribution<double> step(0, 0.05 * span), noise(0, jitter * span);
  std::vector<double> plateau(64);
  for (double& p : plateau) p = step(rng);
  return make_depth(w, h, [&](int col, int row) {
    const double smooth =
        0.5 + 0.25 * std::sin(col / 37.0) * std::cos(row / 29.0) + 0.2 * (col + row) / (w + h);
    const double steps = col > w / 2 && row > h / 2
                             ? plateau[static_cast<std::size_t>(row / 5 * 8 + col / 7) % 64]
                             : 0.0;
    const double cliff = col == w / 3 ? 0.2 * span : 0.0;
    return static_cast<float>(range.lo + span * 0.8 * smooth + steps + cliff +
                              (jitter > 0 ? noise(rng) : 0.0));
  });
}

DepthImage white_noise(int w, int h, float lo, float span, std::uint32_t& state) {
  return make_depth(w, h, [&](int, int) {
    state = state * 1664525u + 1013904223u;
    return lo + span * (static_cast<float>(state >> 8) * 0x1p-24f);
  });
}

}  // namespace lightvol::test
