// The lattice helpers of the tessellate stage: RowSpanWalker gives exactly triangle_row_span's
// spans row after row (the collapse tessellation's texel loops walk rows with it).
#include <algorithm>
#include <cstdint>
#include <random>

#include <gtest/gtest.h>

#include <lightvol/tessellate/detail/lattice.h>

namespace lightvol {
namespace {

using detail::Pt;
using detail::RowSpanWalker;
using detail::triangle_row_span;

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

}  // namespace
}  // namespace lightvol
