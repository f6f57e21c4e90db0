// The lattice helpers of the tessellate stage: RowSpanWalker gives exactly triangle_row_span's
// spans row after row (the collapse tessellation's texel loops walk rows with it); DepthBounds
// bounds every block's texels, and within_by_bounds proves only triangles the measure finds
// within the bound. box_error_rows and the error pyramid's values are what a plain loop over the
// texels finds.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/tessellate/adaptive_grid.h>
#include <lightvol/tessellate/detail/depth_bounds.h>
#include <lightvol/tessellate/detail/lattice.h>

#include "support/adaptive_support.h"
#include "support/test_support.h"

namespace lightvol {
namespace {

using detail::box_error_rows;
using detail::DepthBounds;
using detail::Pt;
using detail::Quadtree;
using detail::round_up;
using detail::RowSpanWalker;
using detail::triangle_error;
using detail::triangle_row_span;
using detail::within_by_bounds;
using test::LightRange;

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

// box_error_rows one texel at a time: the planes of the cell's triangles through its corners'
// depths and the same operations per texel as error_kernels.cpp (each texel on the triangle the
// diagonal from (x1, y0) to (x0, y1) puts it in, the upper-left one when on it), the rows in order,
// stopping after the first row that takes the largest error past `cap`. *gap: the largest
// |plane − depth| over the rows taken.
double box_error_reference(const TexelDepths& t, const Quadtree::Box& b, int y_begin, int y_end,
                           double cap, double* gap) {
  const int wx = b.x1 - b.x0, wy = b.y1 - b.y0;
  const double da = t.window_depth(b.x0, b.y0), db = t.window_depth(b.x1, b.y0),
               dc = t.window_depth(b.x0, b.y1), dd = t.window_depth(b.x1, b.y1);
  const double g1x = (db - da) / wx, g1y = (dc - da) / wy;
  const double g2x = (dd - dc) / wx, g2y = (dd - db) / wy;
  double worst = 0;
  *gap = 0;
  for (int y = y_begin; y < y_end; ++y) {
    const int s = y - b.y0;
    for (int x = b.x0; x <= b.x1; ++x) {
      const bool upper = std::int64_t{x - b.x0} * wy <= std::int64_t{wx} * (wy - s);
      const double d =
          upper ? (da + g1y * s) + g1x * (x - b.x0) : (dd + g2y * (y - b.y1)) + g2x * (x - b.x1);
      const double a = std::abs(d - t.window_depth(x, y));
      const double e =
          t.uniform() ? a * t.uniform_scale()
                      : a * t.scale_row(y)[x] / std::abs(t.w0(0, y) + t.w0_dc() * x + d * t.w1());
      worst = std::max(worst, e);
      *gap = std::max(*gap, a);
    }
    if (worst > cap) break;
  }
  return worst;
}

// Maps with a smooth surface, plateaus with steps, a cliff and noise, under uniform and per-texel
// error scales, depths held as floats and as doubles, sizes whose border cells are clipped at every
// level.
TexelDepths error_map(const LightRange& c, int w, int h, std::uint32_t seed) {
  std::mt19937 rng(seed);
  // Noise on every texel: the largest error of many cells lies on their diagonal, where the two
  // planes agree only to rounding (the kernels must take the same plane there).
  const DepthImage depth = test::plateau_scene(w, h, c, rng, 1e-3);
  Result<TexelDepths> t = TexelDepths::create(test::light_from_json(c.light), depth, 0, "x");
  EXPECT_TRUE(t.ok());
  return std::move(*t);
}

// Every cell of every level (whole squares of 2 to 256 texels a side, cells clipped at the border),
// all rows and a middle part of them, without a cap and with caps the rows pass at different
// places: exactly the reference's error (and depth gap), for both error scales and depth types.
TEST(BoxErrorRows, SameAsOneTexelAtATime) {
  bool uniform = false, scaled = false, floats = false, doubles = false;
  int capped = 0;
  for (const LightRange& c : test::light_ranges())
    for (const auto& [w, h] : {std::pair{300, 261}, std::pair{129, 129}}) {
      SCOPED_TRACE(c.light + " " + std::to_string(w) + "x" + std::to_string(h));
      const TexelDepths t = error_map(c, w, h, 5);
      (t.uniform() ? uniform : scaled) = true;
      (t.float_depths() ? floats : doubles) = true;
      const Quadtree q(w, h);
      for (int level = 1; level <= q.top; ++level)
        for (int j = 0; j < q.ny(level); ++j)
          for (int i = 0; i < q.nx(level); ++i) {
            const Quadtree::Box b = q.box(level, i, j);
            const int inner = std::min(3, (b.y1 - b.y0) / 2);
            for (const auto& [y_begin, y_end] :
                 {std::pair{b.y0, b.y1 + 1}, std::pair{b.y0 + inner, b.y1 + 1 - inner}}) {
              double gap = 0, want_gap = 0;
              const double inf = std::numeric_limits<double>::infinity();
              const double full = box_error_reference(t, b, y_begin, y_end, inf, &want_gap);
              for (const double cap : {inf, full, std::nextafter(full, 0.0), 0.5 * full, 0.0}) {
                const double want = box_error_reference(t, b, y_begin, y_end, cap, &want_gap);
                capped += want < full;
                ASSERT_EQ(box_error_rows(t, b, y_begin, y_end, cap, &gap), want)
                    << "level " << level << " cell " << i << ", " << j << " rows " << y_begin
                    << ".." << y_end << " cap " << cap;
                ASSERT_EQ(gap, want_gap) << "level " << level << " cell " << i << ", " << j;
                ASSERT_EQ(box_error_rows(t, b, y_begin, y_end, cap), want)
                    << "level " << level << " cell " << i << ", " << j;
              }
            }
          }
    }
  EXPECT_TRUE(uniform && scaled && floats && doubles);
  EXPECT_GT(capped, 1000);  // the caps stop the rows early in many cells
}

// Without a cap every cell is measured: each value is the cell's own measure rounded up to a
// float (over both triangles by the reference; a whole level-1 cell: its five texels between
// corners, TexelDepths::error at the midpoints' depths), maxed with its children's values.
TEST(Pyramid, UncappedValuesAreTheCellsErrorsTexelByTexel) {
  for (const LightRange& c : test::light_ranges())
    for (const auto& [w, h] : {std::pair{300, 261}, std::pair{129, 129}, std::pair{70, 37}}) {
      SCOPED_TRACE(c.light + " " + std::to_string(w) + "x" + std::to_string(h));
      const RefinementPyramid pyramid(error_map(c, w, h, 9), Refinement::max_error);
      const TexelDepths& t = pyramid.texels();
      const Quadtree q(w, h);
      std::vector<float> below;
      for (int level = 1; level <= q.top; ++level) {
        std::vector<float> here(q.cells(level));
        for (int j = 0; j < q.ny(level); ++j)
          for (int i = 0; i < q.nx(level); ++i) {
            const Quadtree::Box b = q.box(level, i, j);
            double own = 0, gap = 0;
            if (level == 1 && b.x1 - b.x0 == 2 && b.y1 - b.y0 == 2) {
              const int x = b.x0, y = b.y0;
              const double da = t.window_depth(x, y), db = t.window_depth(x + 2, y),
                           dc = t.window_depth(x, y + 2), dd = t.window_depth(x + 2, y + 2);
              own = std::max(
                  {t.error(x + 1, y, 0.5 * (da + db)), t.error(x, y + 1, 0.5 * (da + dc)),
                   t.error(x + 1, y + 1, 0.5 * (db + dc)), t.error(x + 2, y + 1, 0.5 * (db + dd)),
                   t.error(x + 1, y + 2, 0.5 * (dc + dd))});
            } else {
              own = box_error_reference(t, b, b.y0, b.y1 + 1,
                                        std::numeric_limits<double>::infinity(), &gap);
            }
            float v = round_up(own);
            for (int cj = 2 * j; level > 1 && cj < std::min(2 * j + 2, q.ny(level - 1)); ++cj)
              for (int ci = 2 * i; ci < std::min(2 * i + 2, q.nx(level - 1)); ++ci)
                v = std::max(v, below[static_cast<std::size_t>(cj) * q.nx(level - 1) + ci]);
            const std::size_t cell = static_cast<std::size_t>(j) * q.nx(level) + i;
            here[cell] = v;
            ASSERT_EQ(pyramid.value(level, cell), v)
                << "level " << level << " cell " << i << ", " << j;
          }
        below = std::move(here);
      }
    }
}

}  // namespace
}  // namespace lightvol
