#include <array>

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

TEST(Mesh, WeldKeepsAMeshWithoutIdenticalPositions) {
  // 0.0 and -0.0 differ in their bits: not welded.
  Mesh m = box(2, 3, 4);
  m.positions.insert(m.positions.end(), {0.0f, -0.0f, 0.0f});
  const Mesh welded = weld_identical_positions(m);
  EXPECT_EQ(welded.positions, m.positions);
  EXPECT_EQ(welded.indices, m.indices);
}

TEST(Mesh, WeldMergesIdenticalPositionsInOrderOfFirstUse) {
  // The box with each face's corners copied (a triangle soup): back to the 8 corners, numbered
  // in the order they first appear, and an unused copy of the first corner at the end goes too.
  const Mesh b = box(2, 3, 4);
  Mesh soup;
  for (const std::uint32_t i : b.indices) {
    const auto p = b.vertex(i);
    soup.positions.insert(soup.positions.end(), p.begin(), p.end());
    soup.indices.push_back(static_cast<std::uint32_t>(soup.indices.size()));
  }
  soup.positions.insert(soup.positions.end(), {0, 0, 0});
  const Mesh welded = weld_identical_positions(soup);
  ASSERT_EQ(welded.num_vertices(), 8u);
  ASSERT_EQ(welded.num_triangles(), 12u);
  EXPECT_EQ(welded.triangle(0), (std::array<std::uint32_t, 3>{0, 1, 2}));
  for (std::size_t t = 0; t < 12; ++t)
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(welded.vertex(welded.indices[3 * t + k]), b.vertex(b.indices[3 * t + k]));
  EXPECT_DOUBLE_EQ(signed_volume(welded), 24.0);
}

TEST(Mesh, WeldOfManyVerticesFindsOneDuplicate) {
  // 300,000 distinct positions and a copy of one of them in the middle.
  Mesh m;
  for (int i = 0; i < 300000; ++i)
    m.positions.insert(m.positions.end(),
                       {static_cast<float>(i % 1000), static_cast<float>(i / 1000), 1});
  m.positions.insert(m.positions.begin() + 3 * 150000, {7, 123, 1});
  m.indices = {0, 1, 150000, 123007, 150000, 2};
  const Mesh welded = weld_identical_positions(m);
  EXPECT_EQ(welded.num_vertices(), 300000u);
  EXPECT_EQ(welded.triangle(1)[0], welded.triangle(1)[1]);  // 123007 is the copy's original
}

}  // namespace
}  // namespace lightvol
