// Adaptive volumes: the tessellation's error bound checked texel by texel against the built volume
// (by ray casting, independently of the quadtree), exact counts for planes, closedness at every
// level difference and size, determinism, the Laplacian mode. The tessellator's own tests are in
// tests/tessellate/adaptive_grid_test.cpp.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/core/limits.h>
#include <lightvol/core/mesh.h>
#include <lightvol/tessellate/adaptive_grid.h>
#include <lightvol/volume/adaptive_volume.h>
#include <lightvol/volume/static_volume.h>

#include "support/adaptive_support.h"
#include "support/test_support.h"

namespace lightvol {
namespace {

using test::adaptive_scene;
using test::directional_json;
using test::expect_valid_volume;
using test::is_closed_and_oriented;
using test::light_from_json;
using test::make_depth;
using test::ray_errors;
using test::RayErrors;
using test::spot_json;
using test::window_scene;

struct Built {
  Mesh mesh;
  AdaptiveReport report;
};

// The quadtree unless asked (this file's exact counts are the quadtree's; collapse_test.cpp checks
// the collapse tessellation's own properties).
Built build(const Light& light, const DepthImage& depth, double e,
            Refinement refinement = Refinement::max_error,
            Tessellation tessellation = Tessellation::quadtree) {
  AdaptiveOptions o;
  o.refinement = refinement;
  o.tessellation = tessellation;
  o.max_error = e;
  o.threshold = e;
  o.measure = true;
  Built b;
  Result<Mesh> mesh = build_adaptive_volume(light, depth, {}, o, "test.exr", &b.report);
  EXPECT_TRUE(mesh.ok()) << mesh.error().message;
  if (mesh) b.mesh = std::move(*mesh);
  return b;
}

// ---- the bound ---------------------------------------------------------------------------------

TEST(Adaptive, BoundHoldsAtEveryTexelDirectionalLinear) {
  const Light light = light_from_json(directional_json("linear"));
  const DepthImage depth = adaptive_scene(97, 81, 7.0);
  for (const double e : {0.5, 0.05, 0.005})
    for (const Tessellation t : {Tessellation::quadtree, Tessellation::collapse}) {
      SCOPED_TRACE(e);
      SCOPED_TRACE(t == Tessellation::collapse ? "collapse" : "quadtree");
      const Built b = build(light, depth, e, Refinement::max_error, t);
      expect_valid_volume(b.mesh);
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
        std::string(enc) == "window" ? window_scene(65, 65) : adaptive_scene(65, 65, 8.0);
    for (const double e : {0.2, 0.01})
      for (const Tessellation t : {Tessellation::quadtree, Tessellation::collapse}) {
        SCOPED_TRACE(e);
        SCOPED_TRACE(t == Tessellation::collapse ? "collapse" : "quadtree");
        const Built b = build(light, depth, e, Refinement::max_error, t);
        expect_valid_volume(b.mesh);
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
  expect_valid_volume(b.mesh);
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
    expect_valid_volume(s.mesh);
    // A sloped plane under a directional light (linear depth is affine in the texel).
    const Light dir = light_from_json(directional_json("linear"));
    const DepthImage slope = make_depth(
        w, h, [](int c, int r) { return static_cast<float>(4.0 + 0.02 * c - 0.01 * r); });
    const Built d = build(dir, slope, 1e-6);
    EXPECT_EQ(d.mesh.num_triangles(), 2u + 12u);  // walls 8, cap 4
    EXPECT_EQ(d.mesh.num_vertices(), 4u + 4u + 1u);
    expect_valid_volume(d.mesh);
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
  o.tessellation = Tessellation::quadtree;
  Result<Mesh> a = build_adaptive_volume(light, depth, {}, o, "rough");
  ASSERT_TRUE(a.ok());
  const VolumeCounts s = static_volume_counts(light.type, 23, 14);
  EXPECT_EQ(a->num_triangles(), s.triangles);
  EXPECT_EQ(a->num_vertices(), s.vertices);
  expect_valid_volume(*a);
}

TEST(Adaptive, SingleSpikeMakesEveryLevelDifference) {
  // A spike in a 129² floor: leaves from level 0 to 6 meet along 2:1 edges, all closed.
  const Light light = light_from_json(directional_json("linear"));
  const DepthImage depth =
      make_depth(129, 129, [](int c, int r) { return (c == 70 && r == 51) ? 2.0f : 6.0f; });
  const Built b = build(light, depth, 0.01);
  expect_valid_volume(b.mesh);
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
      const DepthImage depth = adaptive_scene(w, h, 8.0);
      for (const double e : {1.0, 0.02}) {
        const Built b = build(light, depth, e);
        expect_valid_volume(b.mesh);
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
  const DepthImage depth = adaptive_scene(40, 33, 7.0);
  const Built b = build(light, depth, 0.05);
  expect_valid_volume(b.mesh);
  const RayErrors r = ray_errors(b.mesh, light, depth);
  EXPECT_EQ(r.missed, 0);
  EXPECT_LE(r.max_error, 0.05 + 2e-5);
}

TEST(Adaptive, LightSpaceOutputIsTheWorldVolumeMoved) {
  // Same grid in either frame: same counts, same volume (the view is a rigid motion), closed.
  const Light light = light_from_json(spot_json("linear"));
  const DepthImage depth = adaptive_scene(33, 21, 8.0);
  AdaptiveOptions o;
  o.max_error = 0.02;
  VolumeOptions in_light;
  in_light.space = Space::light;
  Result<Mesh> world = build_adaptive_volume(light, depth, {}, o, "w");
  Result<Mesh> local = build_adaptive_volume(light, depth, in_light, o, "l");
  ASSERT_TRUE(world.ok() && local.ok());
  EXPECT_EQ(world->indices, local->indices);
  expect_valid_volume(*local);
  EXPECT_NEAR(signed_volume(*local), signed_volume(*world), 1e-4 * signed_volume(*world));
}

TEST(Adaptive, Deterministic) {
  const Light light = light_from_json(spot_json("linear"));
  const DepthImage depth = adaptive_scene(200, 150, 8.0);
  const Built a = build(light, depth, 0.01), b = build(light, depth, 0.01);
  EXPECT_EQ(a.mesh.positions, b.mesh.positions);
  EXPECT_EQ(a.mesh.indices, b.mesh.indices);
}

// ---- the Laplacian mode ------------------------------------------------------------------------

TEST(Adaptive, LaplacianModeStaysClosed) {
  const Light light = light_from_json(spot_json("window"));
  const DepthImage depth = window_scene(100, 37);
  std::uint64_t previous = 0;
  for (const double threshold : {0.1, 0.01, 0.001, 0.0}) {
    const Built b = build(light, depth, threshold, Refinement::laplacian);
    expect_valid_volume(b.mesh);
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

// A map whose quadtree at the bound is too large for the memory budget is refused with the
// estimate for the triangles counted, before they are emitted (the quadtree at full resolution on
// noise: a 64 x 64 map, 7,938 triangles), and builds once the budget allows them.
TEST(Adaptive, TessellationBeyondTheMemoryBudgetIsRefused) {
  const Light light = light_from_json(directional_json("linear"));
  std::uint32_t state = 12345;
  const DepthImage depth = test::white_noise(64, 64, 2.0f, 1.0f, state);
  AdaptiveOptions o;
  o.max_error = 1e-6;
  Result<Mesh> built = build_adaptive_volume(light, depth, {}, o, "noise.exr");
  ASSERT_TRUE(built.ok()) << built.error().message;
  Result<TexelDepths> t = TexelDepths::create(light, depth, 0, "noise.exr");
  ASSERT_TRUE(t.ok());
  const bool float_depths = t->float_depths();
  const RefinementPyramid pyramid(std::move(*t), Refinement::max_error);
  const std::uint64_t triangles = pyramid.tessellate(1e-6, true).num_triangles();
  EXPECT_EQ(triangles, std::uint64_t{2} * 63 * 63);
  const std::uint64_t needed = adaptive_memory_bytes(64, 64, 1, triangles, true, float_depths);
  set_memory_budget(needed - 1);
  Result<Mesh> refused = build_adaptive_volume(light, depth, {}, o, "noise.exr");
  const Status expected = check_memory(needed, "noise.exr", "the adaptive volume at this bound");
  set_memory_budget(needed);
  Result<Mesh> allowed = build_adaptive_volume(light, depth, {}, o, "noise.exr");
  set_memory_budget(0);  // back to the default
  ASSERT_FALSE(refused.ok());
  ASSERT_FALSE(expected.ok());
  EXPECT_EQ(refused.error().message, expected.error().message);
  EXPECT_NE(
      refused.error().message.find("noise.exr: the adaptive volume at this bound needs about"),
      std::string::npos)
      << refused.error().message;
  ASSERT_TRUE(allowed.ok()) << allowed.error().message;
  EXPECT_EQ(allowed->indices, built->indices);
}

}  // namespace
}  // namespace lightvol
