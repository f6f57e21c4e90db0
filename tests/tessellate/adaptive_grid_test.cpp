// Adaptive tessellation of one grid: vertices in texel order and all used, forced border vertices,
// and the fix-up that splits a leaf whose configuration breaks the bound. The bound over whole
// volumes is tested in tests/volume/adaptive_volume_test.cpp.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/core/mesh.h>
#include <lightvol/tessellate/adaptive_grid.h>
#include <lightvol/volume/adaptive_volume.h>

#include "support/adaptive_support.h"
#include "support/test_support.h"

namespace lightvol {
namespace {

using test::adaptive_scene;
using test::directional_json;
using test::expect_valid_volume;
using test::light_from_json;
using test::make_depth;
using test::ray_errors;
using test::RayErrors;

TEST(Adaptive, OutputUsesOnlyItsVerticesInTexelOrder) {
  const Light light = light_from_json(directional_json("linear"));
  const DepthImage depth = adaptive_scene(50, 40, 7.0);
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
  expect_valid_volume(*mesh);
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
  expect_valid_volume(*mesh);
  const RayErrors r = ray_errors(*mesh, light, depth);
  EXPECT_EQ(r.missed, 0);
  EXPECT_LE(r.max_error, 1.0 + 1e-5);
}

}  // namespace
}  // namespace lightvol
