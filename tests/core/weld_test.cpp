// weld_identical_positions at the sizes where it splits the vertices into partitions by hash and
// works on them in parallel: the mapping must be the one a first-come map gives, in one thread,
// whatever the partitions and threads.
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <lightvol/core/mesh.h>

namespace lightvol {
namespace {

// The weld by a first-come map of positions' bits, one vertex at a time: each position kept at its
// lowest-numbered vertex, those in vertex order.
Mesh reference_weld(const Mesh& mesh) {
  std::map<std::array<std::uint32_t, 3>, std::uint32_t> index;
  std::vector<std::uint32_t> remap(mesh.num_vertices());
  Mesh out;
  for (std::size_t v = 0; v < mesh.num_vertices(); ++v) {
    std::array<std::uint32_t, 3> bits;
    std::memcpy(bits.data(), &mesh.positions[3 * v], 12);
    const auto [it, fresh] = index.emplace(bits, static_cast<std::uint32_t>(out.num_vertices()));
    if (fresh)
      out.positions.insert(out.positions.end(), &mesh.positions[3 * v], &mesh.positions[3 * v + 3]);
    remap[v] = it->second;
  }
  for (const std::uint32_t i : mesh.indices) out.indices.push_back(remap[i]);
  return out;
}

// `n` vertices drawn from `distinct` positions on a grid (each value also as -0.0 where it is 0,
// which is another position), in random order; and n triangles over them.
Mesh many_duplicates(std::size_t n, std::size_t distinct, std::uint32_t seed) {
  std::mt19937 random(seed);
  std::uniform_int_distribution<std::size_t> pick(0, distinct - 1);
  Mesh m;
  for (std::size_t v = 0; v < n; ++v) {
    const std::size_t i = pick(random);
    const float x = static_cast<float>(i % 100), y = static_cast<float>((i / 100) % 100),
                z = static_cast<float>(i / 10000);
    m.positions.insert(m.positions.end(), {(i & 1) && x == 0 ? -0.0f : x, y, z});
  }
  std::uniform_int_distribution<std::uint32_t> vertex(0, static_cast<std::uint32_t>(n - 1));
  for (std::size_t t = 0; t < 3 * n; ++t) m.indices.push_back(vertex(random));
  return m;
}

TEST(Weld, PartitionedMappingEqualsTheFirstComeMapForAnyThreadCount) {
  // 400,000 vertices at 50,000 positions (about 8 copies each) fall into 16 partitions.
  const Mesh soup = many_duplicates(400000, 50000, 7);
  const Mesh expected = reference_weld(soup);
  ASSERT_LT(expected.num_vertices(), 50001u);
  ASSERT_GT(expected.num_vertices(), 49000u);
  for (const int threads : {1, 2, 8}) {
    SCOPED_TRACE(threads);
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    const Mesh welded = weld_identical_positions(soup);
    // Bit for bit: -0.0 and 0.0 stay two vertices.
    ASSERT_EQ(welded.positions.size(), expected.positions.size());
    EXPECT_EQ(std::memcmp(welded.positions.data(), expected.positions.data(),
                          4 * expected.positions.size()),
              0);
    EXPECT_EQ(welded.indices, expected.indices);
  }
}

TEST(Weld, NegativeZeroIsAnotherPositionInEveryPartition) {
  // 200,000 distinct positions, then each again with its zero coordinates negated: only those
  // without a zero coordinate are duplicates.
  Mesh m;
  for (int i = 0; i < 200000; ++i)
    m.positions.insert(m.positions.end(),
                       {static_cast<float>(i % 500), static_cast<float>(i / 500), 0.0f});
  const std::size_t half = m.num_vertices();
  for (std::size_t v = 0; v < half; ++v)
    for (int k = 0; k < 3; ++k) {
      const float x = m.positions[3 * v + k];
      m.positions.push_back(x == 0 ? -0.0f : x);
    }
  for (std::uint32_t v = 0; v + 2 < m.num_vertices(); v += 3)
    m.indices.insert(m.indices.end(), {v, v + 1, v + 2});
  const Mesh welded = weld_identical_positions(m);
  // Every copy differs in z's sign bit: nothing is welded.
  EXPECT_EQ(welded.num_vertices(), m.num_vertices());
  EXPECT_EQ(welded.indices, m.indices);
}

TEST(Weld, OneDuplicateAmongMillionsAndAllAtOnePosition) {
  Mesh m;
  for (int i = 0; i < 1000000; ++i)
    m.positions.insert(m.positions.end(),
                       {static_cast<float>(i % 1000), static_cast<float>(i / 1000), 0.5f});
  m.positions.insert(m.positions.end(), {999, 999, 0.5f});  // vertex 1,000,000 = vertex 999,999
  m.indices = {0, 999999, 1000000};
  const Mesh welded = weld_identical_positions(m);
  EXPECT_EQ(welded.num_vertices(), 1000000u);
  EXPECT_EQ(welded.indices, (std::vector<std::uint32_t>{0, 999999, 999999}));

  // One partition holds everything: 100,000 copies of one point become vertex 0.
  Mesh same;
  same.positions.assign(300000, 1.25f);
  same.indices = {0, 50000, 99999};
  const Mesh one = weld_identical_positions(same);
  EXPECT_EQ(one.positions, (std::vector<float>{1.25f, 1.25f, 1.25f}));
  EXPECT_EQ(one.indices, (std::vector<std::uint32_t>{0, 0, 0}));
}

TEST(Weld, NanPositionsAreWeldedOnlyWhenTheirBitsAgree) {
  // The reader refuses non-finite positions before welding; the weld itself compares bits.
  Mesh m;
  for (int i = 0; i < 100000; ++i)
    m.positions.insert(m.positions.end(), {static_cast<float>(i), 0, 0});
  const float nan = std::numeric_limits<float>::quiet_NaN();
  m.positions.insert(m.positions.end(), {nan, 0, 0, nan, 0, 0, -nan, 0, 0});
  m.indices = {100000, 100001, 100002};
  const Mesh welded = weld_identical_positions(m);
  EXPECT_EQ(welded.num_vertices(), 100002u);
  EXPECT_EQ(welded.indices, (std::vector<std::uint32_t>{100000, 100000, 100001}));
}

}  // namespace
}  // namespace lightvol
