// Adaptive tessellation: the error bound checked texel by texel against the emitted mesh (by ray
// casting, independently of the quadtree), exact counts for planes, closedness at every level
// difference and size, determinism, forced border vertices, the Laplacian mode.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/core/mesh.h>
#include <lightvol/volume/adaptive_volume.h>
#include <lightvol/volume/static_volume.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

using test::directional_json;
using test::is_closed_and_oriented;
using test::light_from_json;
using test::make_depth;
using test::spot_json;

// ---- the independent measure: every texel's ray against the mesh ------------------------------

struct RayErrors {
  double max_error = 0;
  int missed = 0;  // texels whose ray hits no grid triangle
};

// Projects each triangle of the volume into the light's texel space (through the light's own
// matrices), drops the closing (vertices on the near plane or at the light), and intersects every
// texel ray its footprint covers (Möller–Trumbore in double). The farthest hit along the ray is
// the volume's surface there; its distance to the texel's true point is the texel's error.
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

// Linear depth (world units along the view axis) of a scene under the test lights: a sloped floor,
// box occluders with sharp edges, 1-texel bars, a sphere.
DepthImage scene(int w, int h, double floor_depth) {
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

// Window depths of the same kind of scene, for a window-encoded spot light.
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

struct Built {
  Mesh mesh;
  AdaptiveReport report;
};

Built build(const Light& light, const DepthImage& depth, double e,
            Refinement refinement = Refinement::max_error) {
  AdaptiveOptions o;
  o.refinement = refinement;
  o.max_error = e;
  o.threshold = e;
  o.measure = true;
  Built b;
  Result<Mesh> mesh = build_adaptive_volume(light, depth, {}, o, "test.exr", &b.report);
  EXPECT_TRUE(mesh.ok()) << mesh.error().message;
  if (mesh) b.mesh = std::move(*mesh);
  return b;
}

void expect_valid(const Mesh& mesh) {
  EXPECT_TRUE(is_closed_and_oriented(mesh));
  EXPECT_TRUE(test::has_no_degenerate_triangles(mesh));
  EXPECT_GT(signed_volume(mesh), 0);
}

// ---- the bound ---------------------------------------------------------------------------------

TEST(Adaptive, BoundHoldsAtEveryTexelDirectionalLinear) {
  const Light light = light_from_json(directional_json("linear"));
  const DepthImage depth = scene(97, 81, 7.0);
  for (const double e : {0.5, 0.05, 0.005}) {
    SCOPED_TRACE(e);
    const Built b = build(light, depth, e);
    expect_valid(b.mesh);
    const RayErrors r = ray_errors(b.mesh, light, depth);
    EXPECT_EQ(r.missed, 0);
    EXPECT_LE(r.max_error, e * (1 + 1e-4) + 2e-5);
    // The mesher's own measure agrees with the rays (up to float positions).
    EXPECT_NEAR(b.report.max_error_reached, r.max_error, 1e-4);
    EXPECT_LE(b.report.max_error_reached, e);
    EXPECT_LT(b.report.triangles, static_volume_counts(light.type, 97, 81).triangles);
  }
}

TEST(Adaptive, BoundHoldsAtEveryTexelSpotWindowAndLinear) {
  for (const char* enc : {"window", "linear"}) {
    SCOPED_TRACE(enc);
    const Light light = light_from_json(spot_json(enc));
    const DepthImage depth =
        std::string(enc) == "window" ? window_scene(65, 65) : scene(65, 65, 8.0);
    for (const double e : {0.2, 0.01}) {
      SCOPED_TRACE(e);
      const Built b = build(light, depth, e);
      expect_valid(b.mesh);
      const RayErrors r = ray_errors(b.mesh, light, depth);
      EXPECT_EQ(r.missed, 0);
      EXPECT_LE(r.max_error, e * (1 + 1e-4) + 5e-5);
      EXPECT_LE(b.report.max_error_reached, e);
    }
  }
}

TEST(Adaptive, ThinBarsAreKept) {
  // One-texel bars 2 units above a flat floor: a bound of 0.1 must keep every bar texel.
  const Light light = light_from_json(directional_json("linear"));
  const DepthImage depth =
      make_depth(64, 48, [](int c, int r) { return (c == 17 || r == 30 || c == r) ? 3.0f : 5.0f; });
  const Built b = build(light, depth, 0.1);
  expect_valid(b.mesh);
  const RayErrors r = ray_errors(b.mesh, light, depth);
  EXPECT_EQ(r.missed, 0);
  EXPECT_LE(r.max_error, 0.1 + 2e-5);
}

// ---- exact counts ------------------------------------------------------------------------------

TEST(Adaptive, PlaneFacingTheLightIsTwoTriangles) {
  // Any size: the root cell covers the whole grid, and a plane has no error.
  for (const auto& [w, h] : {std::pair{2, 2}, {3, 5}, {17, 9}, {100, 37}, {129, 129}}) {
    SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h));
    const Light spot = light_from_json(spot_json("window"));
    const Built s = build(spot, test::constant_depth(w, h, 0.97f), 1e-6);
    EXPECT_EQ(s.report.grid_triangles, 2u);
    EXPECT_EQ(s.mesh.num_triangles(), 6u);  // 2 + a fan over the 4 corners
    EXPECT_EQ(s.mesh.num_vertices(), 5u);
    expect_valid(s.mesh);
    // A sloped plane under a directional light (linear depth is affine in the texel).
    const Light dir = light_from_json(directional_json("linear"));
    const DepthImage slope = make_depth(
        w, h, [](int c, int r) { return static_cast<float>(4.0 + 0.02 * c - 0.01 * r); });
    const Built d = build(dir, slope, 1e-6);
    EXPECT_EQ(d.mesh.num_triangles(), 2u + 12u);  // walls 8, cap 4
    EXPECT_EQ(d.mesh.num_vertices(), 4u + 4u + 1u);
    expect_valid(d.mesh);
    const RayErrors r = ray_errors(d.mesh, dir, slope);
    EXPECT_EQ(r.missed, 0);
    EXPECT_LE(r.max_error, 1e-5);
  }
}

TEST(Adaptive, ZeroBoundOnRoughMapIsTheStaticGrid) {
  // Every quad of a map without coplanar neighbours keeps its texels: the static grid's counts.
  const Light light = light_from_json(directional_json("linear"));
  const DepthImage depth = make_depth(23, 14, [](int c, int r) {
    return static_cast<float>(5 + 0.01 * ((c * 7919 + r * 104729 + c * r * 31) % 97));
  });
  AdaptiveOptions o;
  o.max_error = 0;
  Result<Mesh> a = build_adaptive_volume(light, depth, {}, o, "rough");
  ASSERT_TRUE(a.ok());
  const VolumeCounts s = static_volume_counts(light.type, 23, 14);
  EXPECT_EQ(a->num_triangles(), s.triangles);
  EXPECT_EQ(a->num_vertices(), s.vertices);
  expect_valid(*a);
}

TEST(Adaptive, SingleSpikeMakesEveryLevelDifference) {
  // A spike in a 129² floor: leaves from level 0 to 6 meet along 2:1 edges, all closed.
  const Light light = light_from_json(directional_json("linear"));
  const DepthImage depth =
      make_depth(129, 129, [](int c, int r) { return (c == 70 && r == 51) ? 2.0f : 6.0f; });
  const Built b = build(light, depth, 0.01);
  expect_valid(b.mesh);
  EXPECT_GT(b.report.grid_triangles, 20u);
  EXPECT_LT(b.report.grid_triangles, 400u);
  const RayErrors r = ray_errors(b.mesh, light, depth);
  EXPECT_EQ(r.missed, 0);
  EXPECT_LE(r.max_error, 0.01 + 2e-5);
}

// ---- sizes, closedness, determinism ------------------------------------------------------------

TEST(Adaptive, OddAndNonSquareSizesStayClosedAndBounded) {
  for (const auto& [w, h] :
       {std::pair{2, 2}, {3, 5}, {5, 3}, {17, 9}, {100, 37}, {37, 100}, {129, 129}, {130, 66}}) {
    SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h));
    for (const char* kind : {"spot", "directional"}) {
      SCOPED_TRACE(kind);
      const Light light = light_from_json(std::string(kind) == "spot" ? spot_json("linear")
                                                                      : directional_json("linear"));
      const DepthImage depth = scene(w, h, 8.0);
      for (const double e : {1.0, 0.02}) {
        const Built b = build(light, depth, e);
        expect_valid(b.mesh);
        const RayErrors r = ray_errors(b.mesh, light, depth);
        EXPECT_EQ(r.missed, 0);
        EXPECT_LE(r.max_error, e * (1 + 1e-4) + 5e-5);
      }
    }
  }
}

TEST(Adaptive, MirroredLightKeepsOrientation) {
  Light light = light_from_json(directional_json("linear"));
  light.flip_y = true;
  const DepthImage depth = scene(40, 33, 7.0);
  const Built b = build(light, depth, 0.05);
  expect_valid(b.mesh);
  const RayErrors r = ray_errors(b.mesh, light, depth);
  EXPECT_EQ(r.missed, 0);
  EXPECT_LE(r.max_error, 0.05 + 2e-5);
}

TEST(Adaptive, LightSpaceOutputIsTheWorldVolumeMoved) {
  // Same grid in either frame: same counts, same volume (the view is a rigid motion), closed.
  const Light light = light_from_json(spot_json("linear"));
  const DepthImage depth = scene(33, 21, 8.0);
  AdaptiveOptions o;
  o.max_error = 0.02;
  VolumeOptions in_light;
  in_light.space = Space::light;
  Result<Mesh> world = build_adaptive_volume(light, depth, {}, o, "w");
  Result<Mesh> local = build_adaptive_volume(light, depth, in_light, o, "l");
  ASSERT_TRUE(world.ok() && local.ok());
  EXPECT_EQ(world->indices, local->indices);
  expect_valid(*local);
  EXPECT_NEAR(signed_volume(*local), signed_volume(*world), 1e-4 * signed_volume(*world));
}

TEST(Adaptive, Deterministic) {
  const Light light = light_from_json(spot_json("linear"));
  const DepthImage depth = scene(200, 150, 8.0);
  const Built a = build(light, depth, 0.01), b = build(light, depth, 0.01);
  EXPECT_EQ(a.mesh.positions, b.mesh.positions);
  EXPECT_EQ(a.mesh.indices, b.mesh.indices);
}

TEST(Adaptive, OutputUsesOnlyItsVerticesInTexelOrder) {
  const Light light = light_from_json(directional_json("linear"));
  const DepthImage depth = scene(50, 40, 7.0);
  Result<TexelDepths> t = TexelDepths::create(light, depth, 0, "x");
  ASSERT_TRUE(t.ok());
  const RefinementPyramid pyramid(std::move(*t), Refinement::max_error);
  const AdaptiveGrid g = pyramid.tessellate(0.05, true);
  EXPECT_TRUE(std::is_sorted(g.vertices.begin(), g.vertices.end()));
  std::vector<int> uses(g.vertices.size(), 0);
  for (const std::uint32_t v : g.indices) ++uses[v];
  EXPECT_EQ(std::count(uses.begin(), uses.end(), 0), 0);
  for (int side = 0; side < 4; ++side) {
    const int last = (side == kTop || side == kBottom) ? 49 : 39;
    ASSERT_GE(g.border[side].size(), 2u);
    EXPECT_EQ(g.border[side].front(), 0);
    EXPECT_EQ(g.border[side].back(), last);
  }
}

// ---- forced border vertices (omni seams) -------------------------------------------------------

TEST(Adaptive, ForcedBorderTexelsBecomeVertices) {
  const Light light = light_from_json(directional_json("linear"));
  const DepthImage depth = test::constant_depth(37, 29, 5.0f);
  Result<TexelDepths> t = TexelDepths::create(light, depth, 0, "x");
  ASSERT_TRUE(t.ok());
  const RefinementPyramid pyramid(std::move(*t), Refinement::max_error);
  BorderSplits forced;
  forced.side[kTop] = {5, 17};
  forced.side[kRight] = {3};
  forced.side[kBottom] = {35};
  forced.side[kLeft] = {27};
  const AdaptiveGrid g = pyramid.tessellate(0.1, true, forced);
  for (int side = 0; side < 4; ++side)
    for (const int p : forced.side[side])
      EXPECT_TRUE(std::binary_search(g.border[side].begin(), g.border[side].end(), p))
          << side << " " << p;
  EXPECT_GT(g.num_triangles(), 2u);
  Result<Mesh> mesh = assemble_adaptive_volume(light, depth, g, {}, "x");
  ASSERT_TRUE(mesh.ok());
  expect_valid(*mesh);
  EXPECT_EQ(mesh->num_triangles(), adaptive_volume_counts(light.type, g).triangles);
}

// ---- the fix-up: the bound holds for the configuration emitted, not just the unsplit cell -----

TEST(Adaptive, LeafWhoseSplitConfigurationBreaksTheBoundIsSplit) {
  // 17×17 at depth 5, E = 1 world unit (directional, linear: world error = depth error). Forcing
  // the top-border texel 4 splits the level-3 cell [0,8]², so its right neighbour [8,16]×[0,8] (a
  // leaf: its texels and its children's stay within 0.9) gets its left edge split at (8, 4). That
  // midpoint stands 0.9 high and texel (10, 3) 0.4 low; the configuration's fan from (8, 4) lifts
  // (10, 3) by 3/4 · 0.9 and misses it by 1.075: the leaf must split.
  const Light light = light_from_json(directional_json("linear"));
  const DepthImage depth = make_depth(17, 17, [](int c, int r) {
    if (c == 8 && r == 4) return 5.9f;
    if (c == 10 && r == 3) return 4.6f;
    return 5.0f;
  });
  Result<TexelDepths> t = TexelDepths::create(light, depth, 0, "x");
  ASSERT_TRUE(t.ok());
  const RefinementPyramid pyramid(std::move(*t), Refinement::max_error);
  BorderSplits forced;
  forced.side[kTop] = {4};
  const AdaptiveGrid g = pyramid.tessellate(1.0, true, forced);
  EXPECT_EQ(g.fixup_rounds, 1);
  EXPECT_LE(pyramid.measure(g), 1.0);
  Result<Mesh> mesh = assemble_adaptive_volume(light, depth, g, {}, "x");
  ASSERT_TRUE(mesh.ok());
  expect_valid(*mesh);
  const RayErrors r = ray_errors(*mesh, light, depth);
  EXPECT_EQ(r.missed, 0);
  EXPECT_LE(r.max_error, 1.0 + 1e-5);
}

// ---- the Laplacian mode ------------------------------------------------------------------------

TEST(Adaptive, LaplacianModeStaysClosed) {
  const Light light = light_from_json(spot_json("window"));
  const DepthImage depth = window_scene(100, 37);
  std::uint64_t previous = 0;
  for (const double threshold : {0.1, 0.01, 0.001, 0.0}) {
    const Built b = build(light, depth, threshold, Refinement::laplacian);
    expect_valid(b.mesh);
    EXPECT_GE(b.report.triangles, previous);  // a lower threshold never coarsens
    previous = b.report.triangles;
  }
  // Threshold 0 on a map with curvature everywhere except planes: the flat floor (linear in
  // window depth along rows) still collapses where the Laplacian vanishes.
  EXPECT_LE(previous, static_volume_counts(light.type, 100, 37).triangles);
}

TEST(Adaptive, RadialDepthNoParallelRayReachesIsAnError) {
  const Light light = light_from_json(directional_json("radial"));
  const DepthImage depth = test::constant_depth(8, 8, 0.5f);
  AdaptiveOptions o;
  Result<Mesh> mesh = build_adaptive_volume(light, depth, {}, o, "r.exr");
  ASSERT_FALSE(mesh.ok());
  EXPECT_NE(mesh.error().message.find("r.exr: pixel (0, 0): radial depth"), std::string::npos)
      << mesh.error().message;
}

}  // namespace
}  // namespace lightvol
