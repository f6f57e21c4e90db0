#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include <lightvol/check/check.h>
#include <lightvol/volume/adaptive_volume.h>
#include <lightvol/volume/static_volume.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

constexpr double kTan30 = 0.57735026918962576;

Mesh build(const Light& light, const DepthImage& depth, Space space = Space::world) {
  Result<Mesh> m = build_static_volume(light, depth, {space}, "depth.exr");
  EXPECT_TRUE(m.ok()) << (m.ok() ? "" : m.error().message);
  return m.ok() ? std::move(*m) : Mesh{};
}

// A depth map with a raised box occluder and a sloped floor: not flat anywhere it matters.
DepthImage occluded(int w, int h) {
  return test::make_depth(w, h, [w, h](int c, int r) {
    const bool box = c > w / 4 && c < w / 2 && r > h / 3 && r < 2 * h / 3;
    return box ? 2.0f : 3.0f + 0.05f * static_cast<float>(c) + 0.02f * static_cast<float>(r);
  });
}

TEST(StaticVolume, ClosedFormCounts) {
  EXPECT_EQ(static_volume_counts(LightType::spot, 1024, 1024).triangles, 2'093'058u + 4 * 1023u);
  EXPECT_EQ(static_volume_counts(LightType::spot, 1024, 1024).triangles, 2u * 1024 * 1024 - 2);
  EXPECT_EQ(static_volume_counts(LightType::spot, 4096, 4096).triangles - 4 * 4095u, 33'538'050u);
}

TEST(StaticVolume, SpotExactCountsClosedOutwardNoDegenerates) {
  const Light light = test::light_from_json(test::spot_json("linear", 1.3));
  for (auto [w, h] : {std::pair{2, 2}, {3, 3}, {4, 4}, {5, 3}, {2, 7}, {16, 9}, {33, 32}}) {
    SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h));
    const Mesh m = build(light, occluded(w, h));
    EXPECT_EQ(m.num_vertices(), static_cast<std::size_t>(w * h + 1));
    EXPECT_EQ(m.num_triangles(),
              static_cast<std::size_t>(2 * (w - 1) * (h - 1) + 2 * (w - 1) + 2 * (h - 1)));
    if (w == h) {
      EXPECT_EQ(m.num_triangles(), static_cast<std::size_t>(2 * w * w - 2));
    }
    EXPECT_TRUE(test::is_closed_and_oriented(m));
    EXPECT_TRUE(test::has_no_degenerate_triangles(m));
    EXPECT_GT(signed_volume(m), 0);
  }
}

TEST(StaticVolume, DirectionalExactCountsClosedOutward) {
  const Light light = test::light_from_json(test::directional_json("linear"));
  for (auto [w, h] : {std::pair{2, 2}, {3, 3}, {6, 4}, {3, 8}, {17, 17}}) {
    SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h));
    const Mesh m = build(light, occluded(w, h));
    const std::size_t border = 2 * (w - 1) + 2 * (h - 1);
    EXPECT_EQ(m.num_vertices(), static_cast<std::size_t>(w * h) + border + 1);
    EXPECT_EQ(m.num_triangles(), static_cast<std::size_t>(2 * (w - 1) * (h - 1)) + 3 * border);
    EXPECT_TRUE(test::is_closed_and_oriented(m));
    EXPECT_TRUE(test::has_no_degenerate_triangles(m));
    EXPECT_GT(signed_volume(m), 0);
  }
}

TEST(StaticVolume, DirectionalDepthsOnTheNearPlaneStayJustBeyondIt) {
  // Depth 0 is the near plane (the light at y = 4 looks down −y, near 0): such texels would put
  // their vertices in the cap's plane (zero-height walls, grid faces on the cap). They are kept
  // Unprojector::min_t() down their rays, and the static and adaptive volumes pass every check.
  for (const char* encoding : {"window", "linear"}) {
    const Light light = test::light_from_json(test::directional_json(encoding));
    const double far_value = std::string(encoding) == "window" ? 0.5 : 5.0;
    const Unprojector unproject(light, 7, 5, 0, Space::world);
    const double min_y = 4 - unproject.min_t() * 10;  // ray length 10
    EXPECT_GT(unproject.min_t(), 0);
    EXPECT_LT(unproject.min_t(), 1e-5);
    // All on the near plane; only the border on it; only interior texels on it.
    for (int pattern = 0; pattern < 3; ++pattern) {
      SCOPED_TRACE(std::string(encoding) + " pattern " + std::to_string(pattern));
      const DepthImage depth = test::make_depth(7, 5, [&](int c, int r) {
        const bool border = c == 0 || r == 0 || c == 6 || r == 4;
        const bool on_near = pattern == 0 || (pattern == 1) == border;
        return on_near ? 0.0f : static_cast<float>(far_value);
      });
      const Mesh static_mesh = build(light, depth);
      AdaptiveOptions ao;
      ao.max_error = 0.01;
      const Result<Mesh> adaptive = build_adaptive_volume(light, depth, {}, ao, "depth.exr");
      ASSERT_TRUE(adaptive.ok());
      for (const Mesh* m : {&static_mesh, &*adaptive}) {
        const CheckReport report = check_volume_linear(*m, &light);
        EXPECT_TRUE(report.valid()) << report.first_failure();
        // Grid vertices (the first W·H of the static mesh) of near-plane texels sit at min_y.
        for (std::size_t v = 0; m == &static_mesh && v < 35; ++v)
          if (depth.values[v] == 0) {
            EXPECT_NEAR(m->positions[3 * v + 1], min_y, 1e-6);
          }
      }
    }
  }
}

TEST(StaticVolume, SpotOverFlatFloorIsThePyramid) {
  // Floor at eye distance 4 (world y = 0): the grid is the rectangle through the texel centres,
  // the volume the pyramid over it with height 4.
  for (auto [w, h] : {std::pair{2, 2}, {9, 7}, {64, 48}}) {
    const double aspect = 1.25;
    const Light light = test::light_from_json(test::spot_json("linear", aspect));
    const Mesh m = build(light, test::constant_depth(w, h, 4.0f));
    const double half_x = 4 * kTan30 * aspect * (1.0 - 1.0 / w);
    const double half_y = 4 * kTan30 * (1.0 - 1.0 / h);
    const double pyramid = (2 * half_x) * (2 * half_y) * 4 / 3;
    EXPECT_NEAR(signed_volume(m), pyramid, 1e-5 * pyramid) << w << "x" << h;
  }
}

TEST(StaticVolume, DirectionalVolumeIsTheHeightFieldIntegral) {
  // Linear depth z(c, r) below the near plane (near 0): the volume between the cap and a
  // triangulated height field is Σ area · mean height over the grid triangles.
  const int w = 9, h = 6;
  const DepthImage d = occluded(w, h);
  const Mesh m = build(test::light_from_json(test::directional_json("linear")), d);
  const double dx = 10.0 / w, dy = 8.0 / h;
  double expected = 0;
  for (int r = 0; r + 1 < h; ++r)
    for (int c = 0; c + 1 < w; ++c) {
      const double a = d.at(c, r), b = d.at(c + 1, r), cc = d.at(c, r + 1), dd = d.at(c + 1, r + 1);
      expected += 0.5 * dx * dy * ((a + b + cc) / 3 + (b + dd + cc) / 3);
    }
  EXPECT_NEAR(signed_volume(m), expected, 1e-5 * expected);
}

TEST(StaticVolume, FlipYAndLightSpaceStayOutward) {
  Light light = test::light_from_json(test::spot_json("window"));
  const DepthImage d = test::make_depth(
      8, 5, [](int c, int r) { return 0.9f + 0.01f * static_cast<float>((c * 7 + r * 3) % 5); });
  const double reference = signed_volume(build(light, d));
  light.flip_y = true;
  const Mesh flipped = build(light, d);
  EXPECT_TRUE(test::is_closed_and_oriented(flipped));
  EXPECT_GT(signed_volume(flipped), 0);
  const Mesh eye = build(light, d, Space::light);
  EXPECT_TRUE(test::is_closed_and_oriented(eye));
  EXPECT_NEAR(signed_volume(eye), signed_volume(flipped), 1e-4 * reference);
}

TEST(StaticVolume, MirroringViewMatrixStaysOutward) {
  // A view matrix with a negative determinant (x mirrored) must still give an outward volume.
  const Light base = test::light_from_json(test::spot_json("linear"));
  std::string view = "[", proj = "[";
  Mat4d mirror = Mat4d::identity();
  mirror(0, 0) = -1;
  const Mat4d v = mirror * base.view;
  for (int i = 0; i < 16; ++i) {
    view += std::to_string(v.m[i]) + (i < 15 ? "," : "]");
    proj += std::to_string(base.projection.m[i]) + (i < 15 ? "," : "]");
  }
  const Light light = test::light_from_json(R"({"type":"spot","depth":"linear","view":)" + view +
                                            R"(,"projection":)" + proj + "}");
  const Mesh m = build(light, occluded(6, 5));
  EXPECT_TRUE(test::is_closed_and_oriented(m));
  EXPECT_GT(signed_volume(m), 0);
}

TEST(StaticVolume, VerticesSitOnTheirTexelRays) {
  const Light light = test::light_from_json(test::spot_json("radial"));
  const DepthImage d = occluded(5, 4);
  const Mesh m = build(light, d);
  const Unprojector u(light, 5, 4, 0, Space::world);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 5; ++c) {
      Vec3d p;
      ASSERT_TRUE(u.point(c, r, d.at(c, r), &p));
      const auto v = m.vertex(static_cast<std::size_t>(r * 5 + c));
      EXPECT_NEAR(v[0], p.x, 1e-5);
      EXPECT_NEAR(v[1], p.y, 1e-5);
      EXPECT_NEAR(v[2], p.z, 1e-5);
      EXPECT_NEAR(length(Vec3d{v[0], v[1] - 4.0, v[2]}), d.at(c, r), 1e-5);
    }
  const auto apex = m.vertex(20);
  EXPECT_EQ(apex, (std::array<float, 3>{0, 4, 0}));
}

TEST(StaticVolume, UnreachableRadialDepthNamesThePixel) {
  const Light light = test::light_from_json(test::directional_json("radial"));
  DepthImage d = test::constant_depth(4, 4, 8.0f);
  d.values[1 * 4 + 2] = 0.1f;
  Result<Mesh> m = build_static_volume(light, d, {}, "rad.exr");
  ASSERT_FALSE(m.ok());
  EXPECT_NE(m.error().message.find("rad.exr: pixel (2, 1)"), std::string::npos)
      << m.error().message;
}

// The stream of a static volume, collected: what a writer receives.
struct Streamed {
  Status status;
  Mesh mesh;
};
Streamed collect(StaticVolumeStream& stream) {
  Streamed out;
  out.status = stream.positions([&](const float* xyz, std::size_t n) {
    out.mesh.positions.insert(out.mesh.positions.end(), xyz, xyz + 3 * n);
    return true;
  });
  if (!out.status) return out;
  out.status = stream.triangles([&](const std::uint32_t* abc, std::size_t n) {
    out.mesh.indices.insert(out.mesh.indices.end(), abc, abc + 3 * n);
    return true;
  });
  return out;
}

// Streamed row by row (several blocks of rows at these widths) or held, the volume is the same:
// the same positions and triangles in the same order, and the same bounds and signed volume to
// the bit.
TEST(StaticVolumeStream, IsTheHeldVolumeBlockByBlock) {
  const Light lights[] = {test::light_from_json(test::spot_json("linear", 1.3)),
                          test::light_from_json(test::directional_json("linear"))};
  for (const Light& light : lights)
    for (auto [w, h] : {std::pair{2, 2}, {5, 3}, {700, 500}, {3001, 90}})
      for (const Space space : {Space::world, Space::light}) {
        SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h));
        const DepthImage depth = occluded(w, h);
        const Mesh held = build(light, depth, space);
        StaticVolumeStream stream(light, depth, {space}, "depth.exr", "light.json");
        EXPECT_EQ(stream.num_vertices(), held.num_vertices());
        EXPECT_EQ(stream.num_triangles(), held.num_triangles());
        const Streamed s = collect(stream);
        ASSERT_TRUE(s.status.ok()) << s.status.error().message;
        EXPECT_EQ(s.mesh.positions, held.positions);
        EXPECT_EQ(s.mesh.indices, held.indices);
        EXPECT_EQ(stream.volume(), signed_volume(held));  // bit for bit: the same sums
        const Bounds b = bounding_box(held);
        EXPECT_EQ(stream.bounds().min, b.min);
        EXPECT_EQ(stream.bounds().max, b.max);
      }
}

// Refused as the held volume is, with the same message, before any triangle is handed on.
TEST(StaticVolumeStream, RefusesWhatTheHeldVolumeRefuses) {
  const Light radial = test::light_from_json(test::directional_json("radial"));
  DepthImage d = test::constant_depth(4, 4, 8.0f);
  d.values[1 * 4 + 2] = 0.1f;
  StaticVolumeStream unreachable(radial, d, {}, "rad.exr", "light.json");
  const Streamed u = collect(unreachable);
  ASSERT_FALSE(u.status.ok());
  EXPECT_EQ(u.status.error().message,
            build_static_volume(radial, d, {}, "rad.exr").error().message);
  EXPECT_TRUE(u.mesh.indices.empty());

  // A needle of a frustum: float32 collapses faces.
  const Light needle = test::light_from_json(
      R"({"type": "spot", "position": [0, 10, 0], "direction": [0, -1, 0], "up": [0, 0, -1],)"
      R"( "fov_y_deg": 1e-6, "near": 1, "far": 20})");
  const DepthImage depth = occluded(64, 64);
  const Mesh held = build(needle, depth);
  const Status expected = check_representable(held, needle, Space::world, "needle.json");
  ASSERT_FALSE(expected.ok());
  StaticVolumeStream stream(needle, depth, {}, "depth.exr", "needle.json");
  const Streamed s = collect(stream);
  ASSERT_FALSE(s.status.ok());
  EXPECT_EQ(s.status.error().message, expected.error().message);
  EXPECT_TRUE(s.mesh.indices.empty());
}

}  // namespace
}  // namespace lightvol
