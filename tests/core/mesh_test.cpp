#include <gtest/gtest.h>

#include <lightvol/core/mesh.h>

namespace lightvol {
namespace {

// An axis-aligned box [0,a]×[0,b]×[0,c], outward.
Mesh box(float a, float b, float c) {
  Mesh m;
  m.positions = {0, 0, 0, a, 0, 0, a, b, 0, 0, b, 0, 0, 0, c, a, 0, c, a, b, c, 0, b, c};
  m.indices = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
               1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};
  return m;
}

TEST(Mesh, SignedVolumeOfBoxIsItsVolume) { EXPECT_DOUBLE_EQ(signed_volume(box(2, 3, 4)), 24.0); }

TEST(Mesh, InvertedBoxHasNegativeVolume) {
  Mesh m = box(1, 2, 3);
  for (std::size_t t = 0; t < m.num_triangles(); ++t)
    std::swap(m.indices[3 * t], m.indices[3 * t + 1]);
  EXPECT_DOUBLE_EQ(signed_volume(m), -6.0);
}

TEST(Mesh, BoundingBox) {
  Mesh m = box(2, 3, 4);
  for (float& x : m.positions) x -= 1;
  const Bounds b = bounding_box(m);
  EXPECT_EQ(b.min, (std::array<double, 3>{-1, -1, -1}));
  EXPECT_EQ(b.max, (std::array<double, 3>{1, 2, 3}));
  EXPECT_EQ(m.num_vertices(), 8u);
  EXPECT_EQ(m.num_triangles(), 12u);
}

}  // namespace
}  // namespace lightvol
