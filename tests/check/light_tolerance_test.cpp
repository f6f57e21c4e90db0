// The proof from the light judges each face with a tolerance of that face's own rounding: a vertex
// that no face uses, however far, buys no slack for the faces that are broken, and a far vertex
// that faces do use widens the tolerance of those faces only.
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/check/check.h>
#include <lightvol/core/light_side.h>
#include <lightvol/volume/static_volume.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

constexpr int kSize = 16;

// The bundled demo light: a spot at (0, 10, 0) looking down −Y, fov 60°, near 1, far 20.
Light demo_spot() {
  return test::light_from_json(
      R"({"type": "spot", "position": [0, 10, 0], "direction": [0, -1, 0], "up": [0, 0, -1],)"
      R"( "fov_y_deg": 60, "aspect": 1.0, "near": 1, "far": 20, "depth": "window"})");
}

Light demo_directional() {
  return test::light_from_json(
      R"({"type": "directional", "position": [0, 10, 0], "direction": [0, -1, 0],)"
      R"( "up": [0, 0, -1], "ortho": [-5, 5, -5, 5], "near": 1, "far": 20, "depth": "linear"})");
}

// A 16² map: a floor with a raised block in the middle.
DepthImage block_map(bool linear) {
  return test::make_depth(kSize, kSize, [&](int c, int r) {
    const bool block = c >= 5 && c <= 10 && r >= 4 && r <= 9;
    return linear ? (block ? 6.0f : 9.0f) : (block ? 0.93f : 0.97f);
  });
}

Mesh build(const Light& light) {
  Result<Mesh> mesh =
      build_static_volume(light, block_map(light.type == LightType::directional), {}, "map.exr");
  EXPECT_TRUE(mesh.ok());
  return mesh.ok() ? *mesh : Mesh{};
}

bool nesting_passed(const Mesh& mesh, const Light& light) {
  const CheckReport report = check_volume_linear(mesh, &light);
  const CheckResult* nesting = report.find(kCheckNesting);
  EXPECT_NE(nesting, nullptr);
  return nesting && nesting->status == CheckStatus::passed;
}

Mesh with_unused_vertex(Mesh mesh, std::array<float, 3> p) {
  mesh.positions.insert(mesh.positions.end(), p.begin(), p.end());
  return mesh;
}

// Faces judged by the proof keep their own tolerance: the far points a broken volume gets.
const std::vector<std::array<float, 3>> kFarPoints = {
    {0, 1e6f, 0}, {0, 1e7f, 0}, {1e12f, -1e12f, 3e12f}, {0, 3.4e38f, 0}, {-3.4e38f, 0, 0}};

TEST(LightTolerance, ABorderVertexLiftedAboveTheLightIsCaughtWhateverVertexIsAdded) {
  // The case that fooled the proof: border texel (15, 8) of a 16² spot volume lifted through its
  // neighbour to y = 11, above the light (CGAL finds 3 pairs of intersecting faces). A vertex that
  // no face uses, however far, gave every face the tolerance of its coordinate; the lifted faces
  // then counted as edge-on.
  const Light light = demo_spot();
  Mesh mesh = build(light);
  ASSERT_TRUE(nesting_passed(mesh, light));
  const std::uint32_t v = 8 * kSize + 15;
  mesh.positions[3 * v + 1] = 11;
  ASSERT_FALSE(nesting_passed(mesh, light));
  for (const auto& far : kFarPoints) {
    SCOPED_TRACE(testing::Message() << far[0] << " " << far[1] << " " << far[2]);
    const Mesh fooled = with_unused_vertex(mesh, far);
    const CheckReport report = check_volume_linear(fooled, &light);
    EXPECT_FALSE(report.valid());
    const CheckResult* nesting = report.find(kCheckNesting);
    ASSERT_NE(nesting, nullptr);
    EXPECT_EQ(nesting->status, CheckStatus::failed) << nesting->detail;
  }
  // And a sound volume with the same far vertex stays sound.
  for (const auto& far : kFarPoints)
    EXPECT_TRUE(nesting_passed(with_unused_vertex(build(light), far), light));
}

// Property: every single-vertex drag that breaks the proof stays broken when any far vertex is
// added to the file, for spot and directional volumes; and every drag that the proof accepts is
// accepted with it too (unused vertices do not change a verdict at all), and is sound for CGAL.
TEST(LightTolerance, AnUnusedFarVertexNeverChangesTheVerdict) {
  std::mt19937 rng(20261202);
  for (const Light& light : {demo_spot(), demo_directional()}) {
    SCOPED_TRACE(light.type == LightType::spot ? "spot" : "directional");
    const Mesh sound = build(light);
    const std::size_t grid = std::size_t{kSize} * kSize;
    int broken = 0;
    for (int trial = 0; trial < 150; ++trial) {
      Mesh mesh = sound;
      const std::size_t v = std::uniform_int_distribution<std::size_t>(0, grid - 1)(rng);
      std::uniform_real_distribution<float> offset(-3, 3);
      for (int k = 0; k < 3; ++k) mesh.positions[3 * v + k] += offset(rng);
      const bool before = nesting_passed(mesh, light);
      broken += !before;
      // What the proof accepts, CGAL finds no self-intersection in: every ray from the light
      // leaves it once.
      if (before) {
        const CheckReport cgal = check_volume(mesh, nullptr);
        EXPECT_TRUE(cgal.valid()) << "trial " << trial << ": " << cgal.first_failure();
      }
      for (const auto& far : kFarPoints) {
        SCOPED_TRACE(testing::Message() << "trial " << trial << ", vertex " << v << ", far "
                                        << far[0] << " " << far[1] << " " << far[2]);
        EXPECT_EQ(nesting_passed(with_unused_vertex(mesh, far), light), before);
      }
    }
    EXPECT_GT(broken, 50);  // most drags by up to 3 units break the volume
  }
}

TEST(LightTolerance, AUsedFarVertexWidensTheToleranceOfItsOwnFacesOnly) {
  // The corner motion a face is allowed: eight float ulps of its own largest coordinate.
  const Vec3d near{1, 2, 3}, far{0, 1e7, 0};
  EXPECT_EQ(corner_motion(near, near, near), 8 * std::ldexp(3.0, -23));
  EXPECT_EQ(corner_motion(near, far, near), 8 * std::ldexp(1e7, -23));
  EXPECT_EQ(corner_motion({-4, 0, 0}, near, near), 8 * std::ldexp(4.0, -23));
}

}  // namespace
}  // namespace lightvol
