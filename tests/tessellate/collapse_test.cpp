// The "collapse" tessellation (collapse_grid): checked by a brute-force measure that knows nothing
// of how the grid was made: every texel is located in the triangles that hold it (integer
// point-in-triangle tests over each triangle's bounding box), its depth interpolated with
// barycentric weights, and its error taken with TexelDepths::error; the triangulation must tile the
// grid's rectangle exactly (consistent orientation, areas summing to the rectangle, every interior
// edge shared by two triangles in opposite directions, every other edge on the rectangle's border).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <lightvol/tessellate/adaptive_grid.h>
#include <lightvol/tessellate/collapse_grid.h>
#include <lightvol/volume/adaptive_volume.h>
#include <lightvol/volume/static_volume.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

using test::directional_json;
using test::light_from_json;
using test::make_depth;
using test::spot_json;

// Depths of a scene made of what shadow maps are made of: a sloped floor, a box (axis-aligned
// steps), a one-texel bar, a diagonal step and a sphere. `scale` maps [0, 1] to the stored range.
DepthImage scene(int w, int h, double lo, double hi) {
  return make_depth(w, h, [=](int c, int r) {
    const double x = (c + 0.5) / w, y = (r + 0.5) / h;
    double t = 0.9 + 0.05 * x + 0.03 * y * y;
    if (x > 0.15 && x < 0.45 && y > 0.2 && y < 0.4) t = 0.5;  // box
    if (c == w / 2) t = 0.6;                                  // one-texel bar
    if (x + 2 * y > 2.2) t = 0.75 + 0.02 * x;                 // diagonal step
    const double dx = x - 0.7, dy = y - 0.3, rr = dx * dx + dy * dy;
    if (rr < 0.02) t = std::min(t, 0.55 + 2 * rr);  // sphere-like cap
    return static_cast<float>(lo + (hi - lo) * t);
  });
}

struct Pt {
  std::int64_t x, y;
};

Pt texel(const AdaptiveGrid& g, std::uint32_t v) {
  const std::uint32_t id = g.vertices[v];
  return {id % static_cast<std::uint32_t>(g.width), id / static_cast<std::uint32_t>(g.width)};
}

std::int64_t cross(Pt a, Pt b, Pt c) {
  return (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
}

// The triangulation tiles [0, W−1] × [0, H−1] without T-junctions; its border lists match its
// vertices on each side.
::testing::AssertionResult is_conforming(const AdaptiveGrid& g) {
  const std::int64_t w = g.width, h = g.height;
  if (!std::is_sorted(g.vertices.begin(), g.vertices.end()) ||
      std::adjacent_find(g.vertices.begin(), g.vertices.end()) != g.vertices.end())
    return ::testing::AssertionFailure() << "vertices not strictly ascending";
  std::int64_t sign = 0, area2 = 0;
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
  for (std::size_t t = 0; t < g.num_triangles(); ++t) {
    const std::uint32_t* v = &g.indices[3 * t];
    const std::int64_t a = cross(texel(g, v[0]), texel(g, v[1]), texel(g, v[2]));
    if (a == 0) return ::testing::AssertionFailure() << "triangle " << t << " is degenerate";
    if (sign == 0) sign = a > 0 ? 1 : -1;
    if ((a > 0) != (sign > 0))
      return ::testing::AssertionFailure() << "triangle " << t << " flipped";
    area2 += std::abs(a);
    for (int k = 0; k < 3; ++k) ++edges[{v[k], v[(k + 1) % 3]}];
  }
  if (area2 != 2 * (w - 1) * (h - 1))
    return ::testing::AssertionFailure() << "areas sum to " << area2 << "/2, not the rectangle";
  for (const auto& [e, n] : edges) {
    if (n != 1) return ::testing::AssertionFailure() << "edge used " << n << " times one way";
    if (edges.count({e.second, e.first})) continue;
    const Pt a = texel(g, e.first), b = texel(g, e.second);
    const bool on_side =
        (a.x == b.x && (a.x == 0 || a.x == w - 1)) || (a.y == b.y && (a.y == 0 || a.y == h - 1));
    if (!on_side)
      return ::testing::AssertionFailure() << "open edge (" << a.x << ", " << a.y << ")–(" << b.x
                                           << ", " << b.y << ") inside the grid: a T-junction";
  }
  std::vector<int> border[4];
  for (std::uint32_t v = 0; v < g.vertices.size(); ++v) {
    const Pt p = texel(g, v);
    if (p.y == 0) border[kTop].push_back(static_cast<int>(p.x));
    if (p.y == h - 1) border[kBottom].push_back(static_cast<int>(p.x));
  }
  for (std::int64_t r = 0; r < h; ++r)
    for (std::uint32_t v = 0; v < g.vertices.size(); ++v) {
      const Pt p = texel(g, v);
      if (p.y != r) continue;
      if (p.x == 0) border[kLeft].push_back(static_cast<int>(r));
      if (p.x == w - 1) border[kRight].push_back(static_cast<int>(r));
    }
  for (int s = 0; s < 4; ++s)
    if (border[s] != g.border[s])
      return ::testing::AssertionFailure() << "border list of side " << s << " is wrong";
  return ::testing::AssertionSuccess();
}

struct Measured {
  double max_error = 0;
  int uncovered = 0;
};

// Every texel against every triangle holding it (closed triangles: texels on shared edges are
// measured in each).
Measured brute_force(const TexelDepths& t, const AdaptiveGrid& g) {
  Measured m;
  std::vector<std::uint8_t> covered(static_cast<std::size_t>(g.width) * g.height, 0);
  for (std::size_t k = 0; k < g.num_triangles(); ++k) {
    const Pt p[3] = {texel(g, g.indices[3 * k]), texel(g, g.indices[3 * k + 1]),
                     texel(g, g.indices[3 * k + 2])};
    const std::int64_t area = cross(p[0], p[1], p[2]);
    const std::int64_t x0 = std::min({p[0].x, p[1].x, p[2].x}),
                       x1 = std::max({p[0].x, p[1].x, p[2].x});
    const std::int64_t y0 = std::min({p[0].y, p[1].y, p[2].y}),
                       y1 = std::max({p[0].y, p[1].y, p[2].y});
    for (std::int64_t y = y0; y <= y1; ++y)
      for (std::int64_t x = x0; x <= x1; ++x) {
        const Pt q{x, y};
        // Barycentric weights (times the area): all of the area's sign or zero inside.
        const std::int64_t b0 = cross(p[1], p[2], q), b1 = cross(p[2], p[0], q),
                           b2 = cross(p[0], p[1], q);
        const bool inside =
            area > 0 ? (b0 >= 0 && b1 >= 0 && b2 >= 0) : (b0 <= 0 && b1 <= 0 && b2 <= 0);
        if (!inside) continue;
        const double d = (static_cast<double>(b0) * t.window_depth(int(p[0].x), int(p[0].y)) +
                          static_cast<double>(b1) * t.window_depth(int(p[1].x), int(p[1].y)) +
                          static_cast<double>(b2) * t.window_depth(int(p[2].x), int(p[2].y))) /
                         static_cast<double>(area);
        m.max_error = std::max(m.max_error, t.error(int(x), int(y), d));
        covered[static_cast<std::size_t>(y) * g.width + x] = 1;
      }
  }
  m.uncovered = static_cast<int>(std::count(covered.begin(), covered.end(), 0));
  return m;
}

struct Case {
  std::string name;
  Light light;
  DepthImage depth;
};

std::vector<Case> cases(int w, int h) {
  return {{"directional linear", light_from_json(directional_json("linear")), scene(w, h, 2, 9)},
          {"spot window", light_from_json(spot_json("window")), scene(w, h, 0.9, 0.999)},
          {"spot linear", light_from_json(spot_json("linear")), scene(w, h, 1, 8)}};
}

TexelDepths texels_of(const Case& c) {
  Result<TexelDepths> t = TexelDepths::create(c.light, c.depth, 0, "test.exr");
  EXPECT_TRUE(t.ok());
  return std::move(*t);
}

TEST(Collapse, BoundHoldsAtEveryTexelAndTheGridStaysConforming) {
  for (const auto& [w, h] :
       {std::pair{97, 81}, std::pair{64, 33}, std::pair{3, 70}, std::pair{2, 2}}) {
    for (const Case& c : cases(w, h)) {
      SCOPED_TRACE(c.name + " " + std::to_string(w) + "x" + std::to_string(h));
      const RefinementPyramid pyramid(texels_of(c), Refinement::max_error);
      // Bounds relative to the scene's largest error, so that every light sees coarse and fine.
      const double top = pyramid.measure(pyramid.tessellate(1e30, true));
      for (const double f : {0.5, 0.05, 0.002}) {
        const double e = std::max(top * f, 1e-9);
        SCOPED_TRACE(e);
        for (const bool standard : {true, false}) {
          const AdaptiveGrid quad = pyramid.tessellate(e, standard);
          CollapseReport report;
          const AdaptiveGrid g = collapse_grid(pyramid.texels(), quad, e, {}, &report);
          EXPECT_TRUE(is_conforming(g));
          const Measured m = brute_force(pyramid.texels(), g);
          EXPECT_EQ(m.uncovered, 0);
          EXPECT_LE(m.max_error, e * (1 + 1e-9));
          EXPECT_LE(g.num_triangles(), quad.num_triangles());
          EXPECT_GE(grid_quality(g).min_height, CollapseOptions{}.min_height);
          // Winding kept: the first triangle turns the same way as the quadtree's.
          const auto turn = [](const AdaptiveGrid& a) {
            return cross(texel(a, a.indices[0]), texel(a, a.indices[1]), texel(a, a.indices[2])) >
                   0;
          };
          EXPECT_EQ(turn(g), turn(quad));
          EXPECT_EQ(report.collapses, quad.vertices.size() - g.vertices.size());
        }
      }
    }
  }
}

TEST(Collapse, FarFewerTrianglesThanTheQuadtreeOnSteps) {
  const Case c = cases(129, 129)[0];
  const RefinementPyramid pyramid(texels_of(c), Refinement::max_error);
  const double e = 1e-3;
  const AdaptiveGrid quad = pyramid.tessellate(e, true);
  const AdaptiveGrid g = collapse_grid(pyramid.texels(), quad, e);
  EXPECT_TRUE(is_conforming(g));
  EXPECT_LE(brute_force(pyramid.texels(), g).max_error, e);
  EXPECT_LT(3 * g.num_triangles(), quad.num_triangles());
}

TEST(Collapse, PlaneInWindowDepthIsTwoTriangles) {
  // A plane in window depth (the directional light's linear depth is affine in window depth): any
  // triangle interpolates it exactly, so everything but the corners collapses.
  const Light light = light_from_json(directional_json("linear"));
  const DepthImage depth =
      make_depth(50, 37, [](int c, int r) { return float(3 + 0.01 * c + 0.02 * r); });
  Result<TexelDepths> t = TexelDepths::create(light, depth, 0, "plane.exr");
  ASSERT_TRUE(t.ok());
  const RefinementPyramid pyramid(std::move(*t), Refinement::max_error);
  // Start from a fine grid (bound 0 keeps every texel whose float depth is off the plane) to make
  // the collapses do the work.
  const AdaptiveGrid full = pyramid.tessellate(0, true);
  ASSERT_GT(full.num_triangles(), 1000u);
  const AdaptiveGrid g = collapse_grid(pyramid.texels(), full, 1e-6);
  EXPECT_TRUE(is_conforming(g));
  EXPECT_EQ(g.num_triangles(), 2u);
  EXPECT_EQ(g.vertices.size(), 4u);
}

TEST(Collapse, FlipsTheLongDiagonalWhenTheBoundAllows) {
  // A 11×3 grid on a plane in window depth (any triangle meets any bound), every side locked so no
  // vertex can go: (0,0) (10,0) on top, (0,2) (5,2) (10,2) below, triangulated with the long
  // diagonal (0,0)–(10,2) (smallest angle 10.5°, at (0,0)). Flipping it to (5,2)–(10,0) raises the
  // smallest angle to 21.8°; with flips off it stays.
  const Light light = light_from_json(directional_json("linear"));
  const DepthImage depth =
      make_depth(11, 3, [](int c, int r) { return float(3 + 0.01 * c + 0.02 * r); });
  Result<TexelDepths> t = TexelDepths::create(light, depth, 0, "plane.exr");
  ASSERT_TRUE(t.ok());
  AdaptiveGrid in;
  in.width = 11, in.height = 3;
  in.vertices = {0, 10, 22, 27, 32};  // (0,0) (10,0) (0,2) (5,2) (10,2)
  in.indices = {0, 2, 3, 0, 3, 4, 0, 4, 1};
  in.border[kTop] = {0, 10};
  in.border[kBottom] = {0, 5, 10};
  in.border[kLeft] = {0, 2};
  in.border[kRight] = {0, 2};
  ASSERT_TRUE(is_conforming(in));
  CollapseOptions o;
  for (bool& side : o.locked) side = true;
  CollapseReport report;
  const AdaptiveGrid flipped = collapse_grid(*t, in, 1e-3, o, &report);
  EXPECT_TRUE(is_conforming(flipped));
  EXPECT_EQ(flipped.vertices, in.vertices);
  EXPECT_EQ(report.flips, 1u);
  EXPECT_NEAR(grid_quality(in).min_angle_degrees,
              (std::atan2(2.0, 5.0) - std::atan2(2.0, 10.0)) * 180 / M_PI, 1e-9);
  EXPECT_NEAR(grid_quality(flipped).min_angle_degrees, std::atan2(2.0, 5.0) * 180 / M_PI, 1e-9);
  o.flip_sweeps = 0;
  const AdaptiveGrid kept = collapse_grid(*t, in, 1e-3, o, &report);
  EXPECT_EQ(report.flips, 0u);
  EXPECT_EQ(kept.indices, in.indices);
}

TEST(Collapse, FastFlipsMakeTheReferenceFlips) {
  // The flip sweeps skip the tries that cannot succeed and compare angles exactly before atan2:
  // the same flips as trying every triangle every sweep on atan2 values, on every case and bound
  // (several sweeps each, so skipped and retried triangles both occur).
  int compared = 0;
  for (const Case& c : cases(97, 131)) {
    const RefinementPyramid pyramid(texels_of(c), Refinement::max_error);
    const double e0 = pyramid.measure(pyramid.tessellate(1e30, true));
    for (const double f : {0.003, 0.01, 0.05}) {
      const AdaptiveGrid quadtree = pyramid.tessellate(e0 * f, true);
      CollapseOptions fast, reference;
      reference.reference_flips = true;
      CollapseReport rf, rr;
      const AdaptiveGrid a = collapse_grid(pyramid.texels(), quadtree, e0 * f, fast, &rf);
      const AdaptiveGrid b = collapse_grid(pyramid.texels(), quadtree, e0 * f, reference, &rr);
      EXPECT_EQ(rf.flips, rr.flips) << c.name << " " << f;
      EXPECT_EQ(a.vertices, b.vertices) << c.name << " " << f;
      EXPECT_EQ(a.indices, b.indices) << c.name << " " << f;
      compared += rf.flips > 0;
    }
  }
  EXPECT_GE(compared, 6);  // flips were made, so the comparison says something
}

TEST(Collapse, TexelTestsByDepthBoundsMakeTheMeasuredGrid) {
  // The texel tests first try the depth bounds (uniform error scales): the same collapses and
  // flips as measuring every new triangle's texels, on every case (a spot light's varying scale
  // takes the plain path in both) and bound, and on plateaus with steps where the bounds prove
  // most floor triangles.
  std::vector<Case> all = cases(97, 131);
  all.push_back({"directional steps", light_from_json(directional_json("linear")),
                 make_depth(130, 97, [](int c, int r) {
                   const int pc = c / 2 * 2, pr = r % 16 / 2 * 2;
                   if (pc < 2) return 0.7f;
                   if (pc % 8 == 0 && pr == 4) return 0.5009f;
                   if (pc % 8 == 2 && pr == 2) return 0.4996f;
                   return 0.5f;
                 })});
  int collapses = 0;
  for (const Case& c : all) {
    const RefinementPyramid pyramid(texels_of(c), Refinement::max_error);
    const double e0 = pyramid.measure(pyramid.tessellate(1e30, true));
    for (const double f : {0.003, 0.01, 0.05, 0.5}) {
      const double e = c.name == "directional steps" ? 0.001 * f / 0.05 : e0 * f;
      const AdaptiveGrid quadtree = pyramid.tessellate(e, true);
      CollapseOptions fast, reference;
      reference.reference_texel_tests = true;
      CollapseReport rf, rr;
      const AdaptiveGrid a = collapse_grid(pyramid.texels(), quadtree, e, fast, &rf);
      const AdaptiveGrid b = collapse_grid(pyramid.texels(), quadtree, e, reference, &rr);
      EXPECT_EQ(rf.collapses, rr.collapses) << c.name << " " << f;
      EXPECT_EQ(rf.attempts, rr.attempts) << c.name << " " << f;
      EXPECT_EQ(rf.flips, rr.flips) << c.name << " " << f;
      EXPECT_EQ(a.vertices, b.vertices) << c.name << " " << f;
      EXPECT_EQ(a.indices, b.indices) << c.name << " " << f;
      EXPECT_LE(brute_force(pyramid.texels(), a).max_error, e * (1 + 1e-9)) << c.name << " " << f;
      collapses += static_cast<int>(rf.collapses);
    }
  }
  EXPECT_GT(collapses, 1000);  // collapses were made, so the comparison says something
}

TEST(Collapse, TheParallelScheduleMakesTheReferenceSchedulesGrids) {
  // All stripes at once (the reference: even ones, then odd ones), the in-order step's collapses
  // and the flips decided ahead in parallel and made in order (the reference: each decided when
  // its turn comes): the same collapses, flips and grids, on every case and bound, with one
  // thread and many. 300 rows: five stripes; the scene's one-texel bar and steps make stars tall
  // enough to cross both kinds of stripe edge.
  std::uint64_t in_order = 0, redecided = 0;
  for (const int threads : {1, 0}) {
    std::optional<tbb::global_control> limit;
    if (threads > 0) limit.emplace(tbb::global_control::max_allowed_parallelism, threads);
    for (const Case& c : cases(97, 300)) {
      const RefinementPyramid pyramid(texels_of(c), Refinement::max_error);
      const double e0 = pyramid.measure(pyramid.tessellate(1e30, true));
      for (const double f : {0.002, 0.01, 0.05}) {
        SCOPED_TRACE(c.name + " " + std::to_string(f) + " threads " + std::to_string(threads));
        const AdaptiveGrid quadtree = pyramid.tessellate(e0 * f, true);
        CollapseOptions reference;
        reference.reference_order = true;
        CollapseReport rp, rr;
        const AdaptiveGrid a = collapse_grid(pyramid.texels(), quadtree, e0 * f, {}, &rp);
        const AdaptiveGrid b = collapse_grid(pyramid.texels(), quadtree, e0 * f, reference, &rr);
        EXPECT_EQ(rp.attempts, rr.attempts);
        EXPECT_EQ(rp.collapses, rr.collapses);
        EXPECT_EQ(rp.flips, rr.flips);
        EXPECT_EQ(rp.rounds, rr.rounds);
        EXPECT_EQ(a.vertices, b.vertices);
        EXPECT_EQ(a.indices, b.indices);
        EXPECT_EQ(rr.in_order_collapses, 0u);
        EXPECT_EQ(rr.flips_redecided, 0u);
        in_order += rp.in_order_collapses;
        redecided += rp.flips_redecided;
      }
    }
  }
  // Both kinds of work decided ahead were made, and decisions were overturned by flips before
  // them: the comparison covers all three parts of the schedule.
  EXPECT_GT(in_order, 0u);
  EXPECT_GT(redecided, 0u);
}

TEST(Collapse, LockedSidesKeepExactlyTheirBorderVertices) {
  const Case c = cases(65, 65)[2];
  const RefinementPyramid pyramid(texels_of(c), Refinement::max_error);
  const double e = pyramid.measure(pyramid.tessellate(1e30, true)) * 0.01;
  BorderSplits forced;
  for (int p = 0; p < 65; p += 3) forced.side[kTop].push_back(p), forced.side[kLeft].push_back(p);
  const AdaptiveGrid quad = pyramid.tessellate(e, true, forced);
  CollapseOptions locked;
  locked.locked[kTop] = locked.locked[kLeft] = true;
  const AdaptiveGrid g = collapse_grid(pyramid.texels(), quad, e, locked);
  EXPECT_TRUE(is_conforming(g));
  EXPECT_LE(brute_force(pyramid.texels(), g).max_error, e);
  EXPECT_EQ(g.border[kTop], quad.border[kTop]);
  EXPECT_EQ(g.border[kLeft], quad.border[kLeft]);
  // The free sides lose vertices (only ever a subset of the quadtree's).
  for (const int s : {kRight, kBottom}) {
    EXPECT_LT(g.border[s].size(), quad.border[s].size());
    EXPECT_TRUE(std::includes(quad.border[s].begin(), quad.border[s].end(), g.border[s].begin(),
                              g.border[s].end()));
  }
}

// Kept positions stay, on a side that is otherwise free; the rest of that side still coarsens
// (an omni seam keeps what the neighbouring face keeps).
TEST(Collapse, KeptBorderPositionsStayAndTheRestOfTheSideCoarsens) {
  const Case c = cases(65, 65)[2];
  const RefinementPyramid pyramid(texels_of(c), Refinement::max_error);
  const double e = pyramid.measure(pyramid.tessellate(1e30, true)) * 0.01;
  BorderSplits forced;
  for (int p = 0; p < 65; p += 2) forced.side[kBottom].push_back(p);
  const AdaptiveGrid quad = pyramid.tessellate(e, true, forced);
  const AdaptiveGrid free_sides = collapse_grid(pyramid.texels(), quad, e);
  // Keep every fourth position of the quadtree's bottom side, and one that has no vertex (ignored).
  CollapseOptions options;
  for (std::size_t k = 0; k < quad.border[kBottom].size(); k += 4)
    options.keep[kBottom].push_back(quad.border[kBottom][k]);
  ASSERT_GE(options.keep[kBottom].size(), 8u);
  const int absent = 1;
  ASSERT_FALSE(
      std::binary_search(quad.border[kBottom].begin(), quad.border[kBottom].end(), absent));
  options.keep[kBottom].insert(options.keep[kBottom].begin() + 1, absent);
  ASSERT_TRUE(std::is_sorted(options.keep[kBottom].begin(), options.keep[kBottom].end()));
  const AdaptiveGrid g = collapse_grid(pyramid.texels(), quad, e, options);
  EXPECT_TRUE(is_conforming(g));
  EXPECT_LE(brute_force(pyramid.texels(), g).max_error, e);
  for (const int p : options.keep[kBottom])
    EXPECT_EQ(std::binary_search(g.border[kBottom].begin(), g.border[kBottom].end(), p),
              p != absent)
        << p;
  // More than the free collapse keeps there, fewer than the quadtree had.
  EXPECT_GT(g.border[kBottom].size(), free_sides.border[kBottom].size());
  EXPECT_LT(g.border[kBottom].size(), quad.border[kBottom].size());
}

TEST(Collapse, SameBytesWithOneThreadAndMany) {
  // 300 rows: five stripes of 64 (and six shifted by 32), coarsened in parallel; the in-order
  // step's collapses and the flips decided ahead in parallel too.
  const Case c = cases(97, 300)[1];
  const RefinementPyramid pyramid(texels_of(c), Refinement::max_error);
  const double e = pyramid.measure(pyramid.tessellate(1e30, true)) * 0.01;
  const AdaptiveGrid many = collapse_grid(pyramid.texels(), pyramid.tessellate(e, true), e);
  AdaptiveGrid one;
  {
    const tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    const RefinementPyramid p1(texels_of(c), Refinement::max_error);
    one = collapse_grid(p1.texels(), p1.tessellate(e, true), e);
  }
  EXPECT_EQ(one.vertices, many.vertices);
  EXPECT_EQ(one.indices, many.indices);
  for (int s = 0; s < 4; ++s) EXPECT_EQ(one.border[s], many.border[s]);
}

TEST(Collapse, QualityReportsTheSmallestAngleAndArea) {
  AdaptiveGrid g;
  g.width = 11, g.height = 2;
  g.vertices = {0, 10, 11, 21};  // (0,0) (10,0) (0,1) (10,1)
  g.indices = {0, 2, 1, 1, 2, 3};
  const GridQuality q = grid_quality(g);
  EXPECT_NEAR(q.min_angle_degrees, std::atan2(1.0, 10.0) * 180 / M_PI, 1e-9);
  EXPECT_DOUBLE_EQ(q.min_area, 5.0);
  EXPECT_NEAR(q.min_height, 10.0 / std::hypot(10.0, 1.0), 1e-12);
}

}  // namespace
}  // namespace lightvol
