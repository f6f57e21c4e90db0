#include <sys/mman.h>

#include <cstddef>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/core/float_buffer.h>

namespace lightvol {
namespace {

// `n` floats 0, 1, 2, ... in an anonymous mapping of whole pages, as a FloatBuffer owning it.
FloatBuffer mapped_ramp(std::size_t n) {
  const std::size_t bytes = n * sizeof(float);
  void* pages = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  EXPECT_NE(pages, MAP_FAILED);
  auto* floats = static_cast<float*>(pages);
  for (std::size_t i = 0; i < n; ++i) floats[i] = static_cast<float>(i);
  return FloatBuffer::adopt_mapping(floats, n, bytes);
}

TEST(FloatBuffer, AMappingIsUsedInPlaceAndMovedWithoutACopy) {
  FloatBuffer buffer = mapped_ramp(4096);
  ASSERT_TRUE(buffer.mapped());
  const float* where = buffer.data();
  EXPECT_EQ(buffer.size(), 4096u);
  EXPECT_EQ(buffer[7], 7.0f);
  buffer[7] = -1;  // private pages: writable
  EXPECT_EQ(buffer[7], -1.0f);
  FloatBuffer moved = std::move(buffer);
  EXPECT_TRUE(moved.mapped());
  EXPECT_EQ(moved.data(), where);  // the pointer is stable across moves
  EXPECT_TRUE(buffer.empty());     // NOLINT(bugprone-use-after-move): moved-from is empty
  EXPECT_FALSE(buffer.mapped());
}

TEST(FloatBuffer, ACopyOrAResizeMovesTheValuesToTheHeap) {
  const FloatBuffer mapped = mapped_ramp(2048);
  FloatBuffer copy = mapped;
  EXPECT_FALSE(copy.mapped());
  EXPECT_NE(copy.data(), mapped.data());
  EXPECT_EQ(copy, mapped);
  FloatBuffer grown = mapped_ramp(2048);
  grown.push_back(2048);
  EXPECT_FALSE(grown.mapped());
  ASSERT_EQ(grown.size(), 2049u);
  for (std::size_t i = 0; i < grown.size(); ++i) EXPECT_EQ(grown[i], static_cast<float>(i));
  FloatBuffer shrunk = mapped_ramp(2048);
  shrunk.resize(3);
  EXPECT_EQ(shrunk, (FloatBuffer{0, 1, 2}));
  FloatBuffer assigned = mapped_ramp(2048);
  assigned.assign(assigned.begin() + 1, assigned.begin() + 3);  // from its own mapped values
  EXPECT_EQ(assigned, (FloatBuffer{1, 2}));
  EXPECT_EQ(assigned.to_vector(), (std::vector<float>{1, 2}));
}

TEST(FloatBuffer, BehavesAsTheVectorItWasMadeFrom) {
  FloatBuffer values = std::vector<float>{3, 1, 2};
  EXPECT_FALSE(values.mapped());
  EXPECT_EQ(values.size(), 3u);
  EXPECT_EQ(values.front(), 3.0f);
  EXPECT_EQ(values.back(), 2.0f);
  float sum = 0;
  for (float v : values) sum += v;
  EXPECT_EQ(sum, 6.0f);
  values.clear();
  EXPECT_TRUE(values.empty());
  values.assign(2, 5.0f);
  EXPECT_EQ(values, (FloatBuffer{5, 5}));
  EXPECT_NE(values, (FloatBuffer{5, 5, 5}));
}

}  // namespace
}  // namespace lightvol
