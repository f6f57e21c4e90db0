// Adaptive tessellation of one grid: vertices in texel order and all used, forced border vertices,
// the fix-up that splits a leaf whose configuration breaks the bound, and its rounds (each re-tests
// only what the round before changed: the same grid as the full rounds); depths held as floats
// when that is exact (the same grids as held as doubles). The bound over whole
// volumes is tested in tests/volume/adaptive_volume_test.cpp.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/core/mesh.h>
#include <lightvol/tessellate/adaptive_grid.h>
#include <lightvol/tessellate/collapse_grid.h>
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
using test::unit_box_json;

// The pyramid of the 50 × 40 test scene under a directional light, linear depth.
RefinementPyramid scene_pyramid() {
  Result<TexelDepths> t = TexelDepths::create(light_from_json(directional_json("linear")),
                                              adaptive_scene(50, 40, 7.0), 0, "x");
  EXPECT_TRUE(t.ok());
  return RefinementPyramid(std::move(*t), Refinement::max_error);
}

TEST(Adaptive, OutputUsesOnlyItsVerticesInTexelOrder) {
  const RefinementPyramid pyramid = scene_pyramid();
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

// A `room` that refuses the leaves' triangles gets their exact number, and nothing is emitted; one
// that accepts them changes nothing.
TEST(Adaptive, RoomIsAskedForTheTrianglesBeforeAnyIsEmitted) {
  const RefinementPyramid pyramid = scene_pyramid();
  const AdaptiveGrid plain = pyramid.tessellate(0.05, true);
  ASSERT_GT(plain.num_triangles(), 0u);
  EXPECT_EQ(plain.refused_triangles, 0u);
  std::vector<std::uint64_t> asked;
  const AdaptiveGrid refused = pyramid.tessellate(0.05, true, {}, [&](std::uint64_t n) {
    asked.push_back(n);
    return false;
  });
  ASSERT_EQ(asked.size(), 1u);
  EXPECT_EQ(asked[0], plain.num_triangles());
  EXPECT_EQ(refused.refused_triangles, plain.num_triangles());
  EXPECT_TRUE(refused.indices.empty());
  EXPECT_TRUE(refused.vertices.empty());
  const AdaptiveGrid accepted =
      pyramid.tessellate(0.05, true, {}, [](std::uint64_t) { return true; });
  EXPECT_EQ(accepted.refused_triangles, 0u);
  EXPECT_EQ(accepted.indices, plain.indices);
  EXPECT_EQ(accepted.vertices, plain.vertices);
}

// ---- depths held as floats ----------------------------------------------------------------------

// TexelDepths holds the window depths as floats when every one is a float exactly: window
// encoding (the stored value clamped to [0, 1]), and a linear encoding whose conversion rounds to
// nothing (an orthographic light from 0 to 1: d = stored). Each depth is checked here against the
// conversion in double precision, so the floats lose nothing; then the pyramid, the quadtree at
// several bounds, the collapsed grid and the measure are the same as with the depths held as
// doubles (both projections: the uniform error scale and the per-texel one). A spot light with
// linear depth (d = a rational function of the stored value) keeps doubles.
TEST(Adaptive, DepthsHeldAsFloatsGiveTheSameGridsAsDoubles) {
  const std::string box = unit_box_json();
  struct Case {
    std::string light;
    double lo, hi;  // stored values, drawn in [lo, hi] on plateaus with steps and slopes
    bool floats;
    bool window;
  };
  const Case cases[] = {{test::spot_json("window"), 0.97, 1.02, true, true},
                        {directional_json("window"), -0.02, 0.6, true, true},
                        {box, 0.05, 0.95, true, false},
                        {test::spot_json("linear"), 2.0, 6.0, false, false}};
  std::mt19937 rng(11);
  for (const Case& c : cases) {
    SCOPED_TRACE(c.light);
    std::uniform_real_distribution<double> value(c.lo, c.hi),
        jitter(-1e-4 * (c.hi - c.lo), 1e-4 * (c.hi - c.lo));
    std::vector<double> plateau(64);
    for (double& p : plateau) p = value(rng);
    const int n = 97;
    const DepthImage depth = make_depth(n, n, [&](int col, int row) {
      const double slope = (c.hi - c.lo) * 0.002 * (col - row);
      return static_cast<float>(plateau[static_cast<std::size_t>(row / 13 * 8 + col / 13) % 64] +
                                slope + jitter(rng));
    });
    const Light light = light_from_json(c.light);
    Result<TexelDepths> held = TexelDepths::create(light, depth, 0, "x");
    ASSERT_TRUE(held.ok());
    EXPECT_EQ(held->float_depths(), c.floats);
    // Each depth against its conversion in double precision (texel_depths.cpp's formulas).
    const Mat4d& pj = light.projection;
    for (int row = 0; row < n; ++row)
      for (int col = 0; col < n; ++col) {
        const double stored = depth.at(col, row);
        double expected = std::clamp(stored, 0.0, 1.0);
        if (!c.window) {
          const double z = -std::clamp(stored, light.near, light.far);
          expected = std::clamp(0.5 * ((pj(2, 2) * z + pj(2, 3)) / (pj(3, 2) * z + pj(3, 3)) + 1.0),
                                0.0, 1.0);
        }
        ASSERT_EQ(held->window_depth(col, row), expected) << col << ", " << row;
      }
    if (!c.floats) continue;
    TexelDepths doubles = held->with_double_depths();
    EXPECT_FALSE(doubles.float_depths());
    EXPECT_EQ(doubles.uniform(), held->uniform());
    const RefinementPyramid as_floats(std::move(*held), Refinement::max_error);
    const RefinementPyramid as_doubles(std::move(doubles), Refinement::max_error);
    for (const double bound : {2e-4, 1e-3, 5e-3}) {
      SCOPED_TRACE(bound);
      const AdaptiveGrid a = as_floats.tessellate(bound, true),
                         b = as_doubles.tessellate(bound, true);
      EXPECT_GT(a.num_triangles(), 2u);
      EXPECT_EQ(a.vertices, b.vertices);
      EXPECT_EQ(a.indices, b.indices);
      EXPECT_EQ(as_floats.measure(a), as_doubles.measure(b));
      const AdaptiveGrid ca = collapse_grid(as_floats.texels(), a, bound),
                         cb = collapse_grid(as_doubles.texels(), b, bound);
      EXPECT_LT(ca.num_triangles(), a.num_triangles());
      EXPECT_EQ(ca.vertices, cb.vertices);
      EXPECT_EQ(ca.indices, cb.indices);
    }
  }
}

// A w × h map repeating 50 values from lo to hi along the diagonals.
DepthImage ramp(int w, int h, float lo, float hi) {
  return make_depth(w, h, [&](int col, int row) {
    return lo + (hi - lo) * static_cast<float>((col * 7 + row * 13) % 50) / 49.0f;
  });
}

// Every texel's window depth the same in both.
void expect_same_depths(const TexelDepths& a, const TexelDepths& b) {
  for (int row = 0; row < a.height(); ++row)
    for (int col = 0; col < a.width(); ++col)
      ASSERT_EQ(a.window_depth(col, row), b.window_depth(col, row)) << col << ", " << row;
}

// With `borrow`, TexelDepths reads the image's floats in place when each is its own window depth
// (window encoding within [0, 1]; an orthographic light from 0 to 1 in linear depth, where d is the
// stored value), and copies otherwise (a window value past 1 is clamped; a spot light's linear
// depths are converted). Borrowed or copied, the same depths and the same grids.
TEST(Adaptive, TexelDepthsBorrowTheImageFloatsWhenTheyAreTheDepths) {
  const std::string box = unit_box_json();
  struct Case {
    std::string light;
    float lo, hi;
    bool borrowed;
  };
  const Case cases[] = {{test::spot_json("window"), 0.9f, 1.0f, true},
                        {test::spot_json("window"), 0.9f, 1.02f, false},
                        {box, 0.05f, 0.95f, true},
                        {test::spot_json("linear"), 2.0f, 6.0f, false}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.light + " " + std::to_string(c.hi));
    const DepthImage depth = ramp(70, 61, c.lo, c.hi);
    const Light light = light_from_json(c.light);
    Result<TexelDepths> lent = TexelDepths::create(light, depth, 0, "x", true);
    Result<TexelDepths> copied = TexelDepths::create(light, depth, 0, "x");
    ASSERT_TRUE(lent.ok() && copied.ok());
    EXPECT_EQ(lent->float_depths() && lent->depth_row_as<float>(0) == depth.values.data(),
              c.borrowed);
    EXPECT_NE(copied->float_depths() ? static_cast<const void*>(copied->depth_row_as<float>(0))
                                     : copied->depth_row_as<double>(0),
              static_cast<const void*>(depth.values.data()));
    expect_same_depths(*lent, *copied);
    const RefinementPyramid a(std::move(*lent), Refinement::max_error),
        b(std::move(*copied), Refinement::max_error);
    const AdaptiveGrid ga = a.tessellate(1e-3, true), gb = b.tessellate(1e-3, true);
    EXPECT_GT(ga.num_triangles(), 2u);
    EXPECT_EQ(ga.indices, gb.indices);
    EXPECT_EQ(ga.vertices, gb.vertices);
  }
}

// The test for borrowing reads the texels in blocks of 65,536 (texel_depths.cpp): one texel that is
// not its own depth, in the last block of a larger image, is enough to copy; without it the
// image is borrowed (a directional light's uniform scale: nothing else is computed).
TEST(Adaptive, TexelDepthsBorrowOnlyWhenEveryBlockHolds) {
  const int w = 301, h = 250;  // 75,250 texels: two blocks
  const std::size_t last = static_cast<std::size_t>(w) * h - 3;
  struct Case {
    std::string light;
    float lo, hi, odd;  // odd: the value of texel `last`, or NaN for none
    bool borrowed;
  };
  const float none = std::numeric_limits<float>::quiet_NaN();
  const Case cases[] = {{unit_box_json(), 0.05f, 0.95f, none, true},
                        {unit_box_json(), 0.05f, 0.95f, 1.5f, false},
                        {test::spot_json("window"), 0.9f, 1.0f, none, true},
                        {test::spot_json("window"), 0.9f, 1.0f, 1.01f, false}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.light + " " + std::to_string(c.odd));
    DepthImage depth = ramp(w, h, c.lo, c.hi);
    if (!std::isnan(c.odd)) depth.values[last] = c.odd;
    const Light light = light_from_json(c.light);
    Result<TexelDepths> lent = TexelDepths::create(light, depth, 0, "x", true);
    Result<TexelDepths> copied = TexelDepths::create(light, depth, 0, "x");
    ASSERT_TRUE(lent.ok() && copied.ok());
    EXPECT_EQ(lent->float_depths() && lent->depth_row_as<float>(0) == depth.values.data(),
              c.borrowed);
    expect_same_depths(*lent, *copied);
    EXPECT_EQ(copied->window_depth(static_cast<int>(last % w), static_cast<int>(last / w)),
              std::isnan(c.odd) ? depth.values[last] : 1.0);
  }
}

// ---- the pyramid capped at the bound
// -------------------------------------------------------------

// A build tessellates at one bound and caps its pyramid there: a cell whose child already exceeds
// the bound is not measured, a measure stops at its first row past it, and a whole cell whose own
// measure and plane gap bound every descendant's within it does not measure its descendants. The
// grids must be those of the uncapped pyramid, cell for cell, at every bound and for every kind of
// projection (spot window and linear: the per-texel error scale; directional: the uniform one,
// whose leaf test takes a shortcut from the pyramid's values), on maps with smooth curves (leaves
// of many levels), plateaus with steps (fix-up rounds) and clipped edge cells (sizes not 2^k + 1),
// with forced border vertices too; and the cap must save measures where leaves are large.
TEST(Adaptive, PyramidCappedAtTheBoundMakesTheUncappedGrids) {
  std::mt19937 rng(5);
  std::uint64_t capped_total = 0, uncapped_total = 0;
  for (const test::LightRange& c : test::light_ranges())
    for (const auto& [w, h] : {std::pair{300, 261}, std::pair{129, 129}}) {
      SCOPED_TRACE(c.light + " " + std::to_string(w) + "x" + std::to_string(h));
      const DepthImage depth = test::plateau_scene(w, h, c, rng);
      const Light light = light_from_json(c.light);
      const auto texels = [&] {
        Result<TexelDepths> t = TexelDepths::create(light, depth, 0, "x");
        EXPECT_TRUE(t.ok());
        return std::move(*t);
      };
      const RefinementPyramid uncapped(texels(), Refinement::max_error);
      BorderSplits forced;
      forced.side[kTop] = {5, w / 2 + 1};
      forced.side[kLeft] = {h / 3};
      for (const double bound : {0.0, 1e-6, 1e-4, 1e-3, 1e-2, 0.1, 10.0}) {
        SCOPED_TRACE(bound);
        const RefinementPyramid capped(texels(), Refinement::max_error, bound);
        EXPECT_EQ(capped.cap(), bound);
        for (const bool force : {false, true}) {
          const BorderSplits none;
          const AdaptiveGrid a = capped.tessellate(bound, true, force ? forced : none),
                             b = uncapped.tessellate(bound, true, force ? forced : none);
          ASSERT_EQ(a.vertices, b.vertices);
          ASSERT_EQ(a.indices, b.indices);
          EXPECT_EQ(a.leaves, b.leaves);
          EXPECT_EQ(a.fixup_rounds, b.fixup_rounds);
        }
        EXPECT_LE(capped.cells_measured(), uncapped.cells_measured());
        capped_total += capped.cells_measured();
        uncapped_total += uncapped.cells_measured();
      }
    }
  // The cap saves: over all cases (bounds 0 and 1e-6 included, where it cannot), fewer than three
  // quarters of the cells are measured (65 % when this test was written).
  EXPECT_LT(4 * capped_total, 3 * uncapped_total) << capped_total << " of " << uncapped_total;
}

TEST(AdaptiveDeathTest, CappedPyramidRefusesABoundAboveItsCap) {
  const Light light = light_from_json(directional_json("linear"));
  Result<TexelDepths> t = TexelDepths::create(light, adaptive_scene(20, 20, 7.0), 0, "x");
  ASSERT_TRUE(t.ok());
  const RefinementPyramid pyramid(std::move(*t), Refinement::max_error, 0.01);
  EXPECT_DEATH(pyramid.tessellate(0.02, true), "bound <= cap_");
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

// ---- the fix-up's rounds: linear in the quadtree's size, the same grid as the full rounds
// --------

// Plateaus with steps that cascade (tests/bench/heightfield_tool's `steps` map): 2×2-texel
// plateaus on a floor at 0.5, in every 8-column, 16-row tile one 0.0009 higher (its texels
// (8k, 4..5) on the left edge of the level-3 cell [8k, 8k+8]) and one 0.0004 lower, and a cliff
// (0.7) in columns 0–1. At E = 0.001 (directional, linear: world error = depth error) every cell
// fits the bound unsplit (0.00085 at most), but once the cell left of [8k, 8k+8] splits, the fan
// from the raised midpoint misses the lowered plateau: it splits too, which splits the next. The
// cliff starts it; the fix-up rounds walk across the map one cell each: n / 8 − 1 rounds.
DepthImage cascading_steps(int n) {
  return make_depth(n, n, [](int c, int r) {
    const int pc = c / 2 * 2, pr = r % 16 / 2 * 2;
    if (pc < 2) return 0.7f;
    if (pc % 8 == 0 && pr == 4) return 0.5009f;
    if (pc % 8 == 2 && pr == 2) return 0.4996f;
    return 0.5f;
  });
}

void expect_same_grid(const AdaptiveGrid& a, const AdaptiveGrid& b) {
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.indices, b.indices);
  for (int side = 0; side < 4; ++side) EXPECT_EQ(a.border[side], b.border[side]) << side;
  EXPECT_EQ(a.leaves, b.leaves);
  EXPECT_EQ(a.fixup_rounds, b.fixup_rounds);
}

TEST(Adaptive, FixupRoundsCascadingAcrossPlateausVisitEachCellAFewTimes) {
  const int n = 256;
  const Light light = light_from_json(directional_json("linear"));
  const DepthImage depth = cascading_steps(n);
  Result<TexelDepths> t = TexelDepths::create(light, depth, 0, "x");
  ASSERT_TRUE(t.ok());
  const RefinementPyramid pyramid(std::move(*t), Refinement::max_error);
  const AdaptiveGrid g = pyramid.tessellate(0.001, true);
  const AdaptiveGrid full = pyramid.tessellate_by_full_rounds(0.001, true);
  EXPECT_EQ(g.fixup_rounds, n / 8 - 1);
  expect_same_grid(g, full);
  EXPECT_LE(pyramid.measure(g), 0.001);
  // The quadtree's cells (levels 1 to 8 over 255 × 255 quads). The full rounds sweep the levels
  // 2 to 8 twice per round; the rounds after the first visit only the splits and their neighbours.
  std::uint64_t cells = 0;
  for (int level = 1; level <= 8; ++level) {
    const std::uint64_t side = (255u + (1u << level) - 1) >> level;
    cells += side * side;
  }
  EXPECT_LE(g.balance_visits, 2 * cells);
  EXPECT_GT(full.balance_visits, 10 * cells);
}

TEST(Adaptive, FixupRoundsGiveTheFullRoundsGridOnRandomPlateaus) {
  // Random variations of cascading_steps: the raised and lowered plateaus 0.75–0.95 and 0.3–0.6
  // of the bound away from the floor, each tile's pair present with probability 0.8 (a missing
  // one stops a cascade), the cliff on the left or not, a floor tilted by up to 0.05 E per texel;
  // under a directional light (uniform error scale) and a spot light (linear depth: the error
  // scale varies over the map); two bounds; a forced border vertex on two sides or none. Every
  // grid equals the full rounds' and meets the bound, and some take many rounds.
  std::mt19937 rng(7);
  const auto uniform = [&](double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng);
  };
  const std::string lights[2] = {directional_json("linear"), test::spot_json("linear")};
  int most_rounds = 0;
  for (int trial = 0; trial < 24; ++trial) {
    const int li = trial % 2, n = (64 << rng() % 3) + 1;
    const double e = trial % 4 < 2 ? 0.001 : 0.01, base = li == 0 ? 5.0 : 3.0;
    const double up = uniform(0.75, 0.95) * e, down = uniform(0.3, 0.6) * e;
    const double tilt_x = uniform(-0.05, 0.05) * e, tilt_y = uniform(-0.05, 0.05) * e;
    const bool cliff = rng() % 4 != 0;
    std::vector<std::uint8_t> present(static_cast<std::size_t>(n) * n);
    for (std::uint8_t& p : present) p = rng() % 5 != 0 ? 1 : 0;
    const int orientation = static_cast<int>(rng() % 8);
    const DepthImage depth = make_depth(n, n, [&](int col, int row) {
      int c = orientation & 1 ? n - 1 - col : col, r = orientation & 2 ? n - 1 - row : row;
      if (orientation & 4) std::swap(c, r);
      const int pc = c / 2 * 2, pr = r % 16 / 2 * 2;
      double v = base + tilt_x * c + tilt_y * r;
      const bool here = present[static_cast<std::size_t>(r / 16) * n + c / 8] != 0;
      if (cliff && pc < 2)
        v = base + 0.2;
      else if (here && pc % 8 == 0 && pr == 4)
        v += up;
      else if (here && pc % 8 == 2 && pr == 2)
        v -= down;
      return static_cast<float>(v);
    });
    const Light light = light_from_json(lights[li]);
    Result<TexelDepths> t = TexelDepths::create(light, depth, 0, "x");
    ASSERT_TRUE(t.ok());
    const RefinementPyramid pyramid(std::move(*t), Refinement::max_error);
    BorderSplits forced;
    if (trial % 3 == 0) {
      forced.side[kTop] = {n / 3};
      forced.side[kRight] = {n / 2 + 1};
    }
    SCOPED_TRACE(testing::Message() << "trial " << trial << ", " << n << "², E " << e);
    const AdaptiveGrid g = pyramid.tessellate(e, true, forced);
    expect_same_grid(g, pyramid.tessellate_by_full_rounds(e, true, forced));
    EXPECT_LE(pyramid.measure(g), e);
    most_rounds = std::max(most_rounds, g.fixup_rounds);
  }
  EXPECT_GE(most_rounds, 5);
}

}  // namespace
}  // namespace lightvol
