// The lattice helpers of the tessellate stage: RowSpanWalker gives exactly triangle_row_span's
// spans row after row (the collapse tessellation's texel loops walk rows with it); DepthBounds
// bounds every block's texels, and within_by_bounds proves only triangles the measure finds
// within the bound.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <utility>

#include <gtest/gtest.h>

#include <lightvol/tessellate/adaptive_grid.h>
#include <lightvol/tessellate/detail/depth_bounds.h>
#include <lightvol/tessellate/detail/lattice.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

using detail::DepthBounds;
using detail::Pt;
using detail::RowSpanWalker;
using detail::triangle_error;
using detail::triangle_row_span;
using detail::within_by_bounds;

std::int64_t cross(Pt a, Pt b, Pt c) {
  return std::int64_t{b.x - a.x} * (c.y - a.y) - std::int64_t{c.x - a.x} * (b.y - a.y);
}

// Every row of the triangle's row range, from its first row or from one inside it.
void expect_same_spans(Pt a, Pt b, Pt c) {
  if (cross(a, b, c) < 0) std::swap(b, c);  // counter-clockwise in texel space
  const Pt v[3] = {a, b, c};
  const int y0 = std::min({a.y, b.y, c.y}), y1 = std::max({a.y, b.y, c.y});
  for (const int start : {y0, (y0 + y1) / 2}) {
    RowSpanWalker walk(v, start);
    for (int y = start; y <= y1; ++y) {
      int x0 = 0, x1 = 0, w0 = 0, w1 = 0;
      const bool want = triangle_row_span(v, y, &x0, &x1);
      ASSERT_EQ(walk.next(&w0, &w1), want) << "row " << y;
      if (want) {
        ASSERT_EQ(w0, x0) << "row " << y;
        ASSERT_EQ(w1, x1) << "row " << y;
      }
    }
  }
}

TEST(RowSpanWalker, SameSpansAsTriangleRowSpan) {
  // Horizontal and vertical edges, a one-sided fan, slivers with empty rows, large coordinates.
  expect_same_spans({0, 0}, {10, 0}, {0, 10});
  expect_same_spans({0, 0}, {10, 10}, {10, 0});
  expect_same_spans({5, 0}, {0, 9}, {9, 9});
  expect_same_spans({0, 0}, {1, 40}, {2, 81});  // thin: most rows hold no lattice point
  expect_same_spans({0, 0}, {40, 1}, {81, 3});  // thin along x
  expect_same_spans({3, 7}, {16383, 16000}, {0, 16383});
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> coord(0, 60);
  int tested = 0;
  while (tested < 3000) {
    const Pt a{coord(rng), coord(rng)}, b{coord(rng), coord(rng)}, c{coord(rng), coord(rng)};
    if (cross(a, b, c) == 0) continue;
    expect_same_spans(a, b, c);
    if (testing::Test::HasFatalFailure()) return;
    ++tested;
  }
}

TEST(DepthBounds, BoundEveryBoxAndProveOnlyWhatTheMeasureConfirms) {
  // Plateaus 0.0009 and 0.0004 off a floor at 0.5 (the bench's steps map, 0.001 of world per
  // unit of depth) with a tilted strip, a cliff on the left, under a directional light (uniform
  // error scale): depths held as floats and as doubles, sizes that clip the blocks.
  int proved = 0, unproved_within = 0;
  for (const auto& [w, h] : {std::pair{203, 77}, std::pair{64, 64}, std::pair{9, 130}}) {
    const DepthImage depth = test::make_depth(w, h, [](int c, int r) {
      const int pc = c / 2 * 2, pr = r % 16 / 2 * 2;
      if (pc < 2) return 0.7f;
      if (pc % 8 == 0 && pr == 4) return 0.5009f;
      if (pc % 8 == 2 && pr == 2) return 0.4996f;
      if (r > 40 && r < 48) return static_cast<float>(0.5 + 1e-5 * c);
      return 0.5f;
    });
    Result<TexelDepths> made = TexelDepths::create(
        test::light_from_json(test::directional_json("linear")), depth, 0, "steps.exr");
    ASSERT_TRUE(made.ok());
    ASSERT_TRUE(made->uniform());
    for (const TexelDepths& t : {made->with_double_depths(), std::move(*made)}) {
      DepthBounds bounds;
      bounds.build(t);
      std::mt19937 rng(11);
      const auto pick = [&](int n) { return static_cast<int>(rng() % static_cast<unsigned>(n)); };
      for (int trial = 0; trial < 3000; ++trial) {
        const int size = 1 << pick(8);
        const Pt a{pick(w), pick(h)};
        const Pt b{std::clamp(a.x + pick(2 * size + 1) - size, 0, w - 1),
                   std::clamp(a.y + pick(2 * size + 1) - size, 0, h - 1)};
        const Pt c{std::clamp(a.x + pick(2 * size + 1) - size, 0, w - 1),
                   std::clamp(a.y + pick(2 * size + 1) - size, 0, h - 1)};
        if (cross(a, b, c) == 0) continue;
        const int x0 = std::min({a.x, b.x, c.x}), x1 = std::max({a.x, b.x, c.x});
        const int y0 = std::min({a.y, b.y, c.y}), y1 = std::max({a.y, b.y, c.y});
        double lo = 0, hi = 0;
        bounds.range(x0, y0, x1, y1, &lo, &hi);
        for (int y = y0; y <= y1; ++y)
          for (int x = x0; x <= x1; ++x) {
            ASSERT_LE(lo, t.window_depth(x, y));
            ASSERT_GE(hi, t.window_depth(x, y));
          }
        const double error = triangle_error(t, a, b, c);
        // Bounds around the 0.0009 of the floor's triangles, and at the measured error itself.
        for (const double bound : {0.0009, 0.00090001, 0.001, 0.0013, error, error * (1 + 1e-15)}) {
          if (within_by_bounds(t, bounds, a, b, c, bound)) {
            ASSERT_LE(error, bound)
                << a.x << "," << a.y << " " << b.x << "," << b.y << " " << c.x << "," << c.y;
            ++proved;
          } else if (error <= bound) {
            ++unproved_within;
          }
        }
      }
    }
  }
  // Both answers occur: the shortcut proves many triangles, and leaves others to the measure.
  EXPECT_GT(proved, 1000);
  EXPECT_GT(unproved_within, 1000);
}

}  // namespace
}  // namespace lightvol
