#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/check/check.h>
#include <lightvol/volume/adaptive_volume.h>
#include <lightvol/volume/build_volume.h>
#include <lightvol/volume/detail/float32_guard.h>
#include <lightvol/volume/float32_guard.h>
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

// The volume before the float32 guard (which refuses it), for the guard's tests.
Mesh unguarded(const Light& light, const DepthImage& depth) {
  Result<Mesh> m = detail::assemble_static_volume(light, depth, {}, "depth.exr");
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

// A directional light box 8193 units wide and 1 deep, and a 513² map with a shadow map's
// structure in [0, 1]: a sloped floor with creases, box occluders, a thin bar.
Light thin_wide_box() {
  return test::light_from_json(
      R"({"type": "directional", "position": [0, 1, 0], "direction": [0, -1, 0], "up": [0, 0, -1],)"
      R"( "ortho": [-4096.5, 4096.5, -4096.5, 4096.5], "near": 0, "far": 1, "depth": "linear"})");
}
DepthImage thin_wide_box_map() {
  return test::make_depth(513, 513, [](int c, int r) {
    if (c > 100 && c < 180 && r > 60 && r < 300) return 0.25f;
    if (c > 300 && c < 304) return 0.4f;
    if ((c - 380) * (c - 380) + (r - 400) * (r - 400) < 40 * 40) return 0.6f;
    return 0.9f + 0.0001f * static_cast<float>(c) - 0.00005f * static_cast<float>(r % 97);
  });
}

// Before: the float32 guard compared the float step at the largest coordinate of any axis (x up to
// 4096.5 here: 4.9e-4) with a spacing derived from the thinnest extent (the box is 1 deep: 1.8e-3
// over 16), and refused this directional volume, although float32 holds it (x steps 4.9e-4
// against a texel 16 wide; no face collapses or turns towards the light). Now it judges the faces
// as the checks do: static and both adaptive tessellations build through build_volume and pass the
// checks with the light.
TEST(StaticVolume, ThinWideDirectionalBoxHoldsInFloat32) {
  const Light light = thin_wide_box();
  const DepthImage depth = thin_wide_box_map();
  for (int mode = 0; mode < 3; ++mode) {
    SCOPED_TRACE(mode == 0 ? "static" : mode == 1 ? "collapse" : "quadtree");
    BuildVolumeOptions options;
    options.grid = mode == 0 ? VolumeGrid::static_grid : VolumeGrid::adaptive;
    options.adaptive.max_error = 0.001;
    options.adaptive.tessellation = mode == 2 ? Tessellation::quadtree : Tessellation::collapse;
    const Result<Mesh> m =
        build_volume(light, ShadowMaps::planar(depth, "wide.exr"), options, nullptr);
    ASSERT_TRUE(m.ok()) << m.error().message;
    EXPECT_TRUE(check_representable(*m, light, Space::world, "wide.json").ok());
    const CheckReport report = check_volume_linear(*m, &light);
    EXPECT_TRUE(report.valid()) << report.first_failure();
  }
}

// The guard is the library's: build_volume refuses what float32 cannot hold (a spot far from the
// origin, a needle of a frustum), naming the light's keys, and accepts the same spot in light
// space.
TEST(StaticVolume, BuildVolumeRefusesWhatFloat32CannotHold) {
  const DepthImage depth = occluded(64, 64);
  const auto spot = [](const std::string& position, const std::string& fov) {
    return test::light_from_json(R"({"type": "spot", "position": )" + position +
                                 R"(, "direction": [0, -1, 0], "up": [0, 0, -1], "fov_y_deg": )" +
                                 fov + R"(, "near": 1, "far": 20, "depth": "linear"})");
  };
  BuildVolumeOptions options;
  options.light_source = "l.json";
  const Result<Mesh> far_away =
      build_volume(spot("[1e6, 10, 0]", "60"), ShadowMaps::planar(depth, "d.exr"), options);
  ASSERT_FALSE(far_away.ok());
  EXPECT_NE(far_away.error().message.find("l.json: float32 cannot hold this volume"),
            std::string::npos)
      << far_away.error().message;
  EXPECT_NE(far_away.error().message.find("key 'position'"), std::string::npos);
  // The library names its own parameter (the CLI says --space light).
  EXPECT_NE(far_away.error().message.find("with VolumeOptions::space = Space::light and place it"),
            std::string::npos)
      << far_away.error().message;
  const Result<Mesh> needle =
      build_volume(spot("[0, 10, 0]", "1e-6"), ShadowMaps::planar(depth, "d.exr"), options);
  ASSERT_FALSE(needle.ok());
  EXPECT_NE(needle.error().message.find("keys 'near', 'far' and 'fov_y_deg'"), std::string::npos)
      << needle.error().message;
  options.space = Space::light;
  const Result<Mesh> in_light_space =
      build_volume(spot("[1e6, 10, 0]", "60"), ShadowMaps::planar(depth, "d.exr"), options);
  ASSERT_TRUE(in_light_space.ok()) << in_light_space.error().message;
}

// The guard runs inside the spot and directional builders, called directly (not only through
// build_volume): static and adaptive refuse the far spot with the light's name and key.
TEST(StaticVolume, BothBuildersRunTheFloat32Guard) {
  const Light far_away = test::light_from_json(
      R"({"type": "spot", "position": [1e6, 10, 0], "direction": [0, -1, 0], "up": [0, 0, -1],)"
      R"( "fov_y_deg": 60, "near": 1, "far": 20, "depth": "linear"})");
  const DepthImage depth = occluded(64, 64);
  VolumeOptions options;
  options.light_source = "l.json";
  AdaptiveOptions adaptive;
  adaptive.max_error = 0.01;
  const Result<Mesh> results[] = {
      build_static_volume(far_away, depth, options, "d.exr"),
      build_adaptive_volume(far_away, depth, options, adaptive, "d.exr")};
  for (const Result<Mesh>& m : results) {
    ASSERT_FALSE(m.ok());
    EXPECT_NE(m.error().message.find("l.json: float32 cannot hold this volume"), std::string::npos)
        << m.error().message;
    EXPECT_NE(m.error().message.find("key 'position'"), std::string::npos);
  }
}

// The guard counts the faces the light proof would see turned towards the light: a sound volume
// has none; reversing one grid face (spot: seen from the apex; directional: an exit facing
// against the light) or one cap face (directional: a near-plane face facing along it) makes one,
// named in the refusal.
TEST(StaticVolume, GuardCountsFacesTurnedTowardsTheLight) {
  const Light spot = test::light_from_json(test::spot_json("linear", 1.3));
  const Light directional = test::light_from_json(test::directional_json("linear"));
  for (const Light* light : {&spot, &directional})
    for (const Space space : {Space::world, Space::light}) {
      const bool is_spot = light == &spot;
      SCOPED_TRACE(std::string(is_spot ? "spot" : "directional") +
                   (space == Space::world ? " world" : " light"));
      const Mesh sound = build(*light, occluded(9, 7), space);
      ASSERT_TRUE(check_representable(sound, *light, space, "l.json").ok());
      // Face 10: a grid face; the last face: the spot's fan, or the directional cap.
      for (const std::size_t face : {std::size_t{10}, sound.num_triangles() - 1}) {
        Mesh turned = sound;
        std::swap(turned.indices[3 * face + 1], turned.indices[3 * face + 2]);
        const Status s = check_representable(turned, *light, space, "l.json");
        if (is_spot && face != 10) {
          // The fan's faces have the apex as a corner: the proof leaves them out.
          EXPECT_TRUE(s.ok());
          continue;
        }
        ASSERT_FALSE(s.ok()) << face;
        EXPECT_NE(s.error().message.find("0 of " + std::to_string(sound.num_triangles()) +
                                         " faces collapse to zero area, 1 face the light"),
                  std::string::npos)
            << s.error().message;
        const Light frame_light = light_in_space(*light, space);
        EXPECT_FALSE(check_volume_linear(turned, &frame_light).valid());
      }
    }
}

TEST(StaticVolume, GuardSettlesFacesInLanesAsItJudgesThemOneByOne) {
  // The guard's face pass settles a point light's faces in vectorized lanes (collapsed, or facing
  // away) and judges the rest one by one; with lanes off it judges every face one by one. Sound,
  // with faces turned, collapsed, or a NaN corner: the same counts, and each break counted.
  const Light spot = test::light_from_json(test::spot_json("linear", 1.3));
  const Mesh sound = build(spot, occluded(300, 200));
  const std::size_t mid = sound.num_triangles() / 2;
  std::vector<std::pair<std::string, Mesh>> variants{{"sound", sound}};
  Mesh turned = sound;
  for (const std::size_t t : {std::size_t{10}, mid, mid + 7})
    std::swap(turned.indices[3 * t + 1], turned.indices[3 * t + 2]);
  variants.emplace_back("turned", turned);
  Mesh collapsed = sound;
  collapsed.indices[3 * 20 + 1] = collapsed.indices[3 * 20];
  const std::uint32_t v = collapsed.indices[3 * mid], w = collapsed.indices[3 * mid + 1];
  for (int k = 0; k < 3; ++k) collapsed.positions[3 * v + k] = collapsed.positions[3 * w + k];
  variants.emplace_back("collapsed", collapsed);
  Mesh nan = sound;
  nan.positions[3 * nan.indices[3 * mid] + 2] = std::numeric_limits<float>::quiet_NaN();
  variants.emplace_back("nan", nan);
  for (const auto& [name, mesh] : variants) {
    SCOPED_TRACE(name);
    const detail::GuardLight guard = detail::guard_light(spot, Space::world);
    const detail::VertexTally vertices =
        detail::tally_vertices(mesh.positions.data(), mesh.num_vertices(), guard);
    const detail::FaceJudge judge(vertices, guard);
    const detail::FaceTally a = detail::tally_faces(mesh, judge, true);
    const detail::FaceTally b = detail::tally_faces(mesh, judge, false);
    EXPECT_EQ(a.triangles, mesh.num_triangles());
    EXPECT_EQ(a.triangles, b.triangles);
    EXPECT_EQ(a.collapsed, b.collapsed);
    EXPECT_EQ(a.turned, b.turned);
    if (name == "sound") {
      EXPECT_EQ(a.collapsed + a.turned, 0u);
    }
    if (name == "turned") {
      EXPECT_EQ(a.turned, 3u);
    }
    if (name == "collapsed") {
      EXPECT_GE(a.collapsed, 3u);  // face 20 and v's faces with w
    }
  }
}

TEST(StaticVolume, ReservedStorageGivesTheSameVolume) {
  // reserve_static_volume's buffers (made while the map is read) are filled in place when they
  // have room: the same positions and triangles, in the storage's own memory; storage for a
  // smaller map is dropped and the volume is the same.
  const Light spot = test::light_from_json(test::spot_json("linear"));
  const Light directional = test::light_from_json(test::directional_json("linear"));
  for (const Light* light : {&spot, &directional}) {
    const DepthImage depth = occluded(40, 30);
    const Mesh plain = build(*light, depth);
    Mesh storage = reserve_static_volume(light->type, 40, 30);
    EXPECT_EQ(storage.num_vertices(), 0u);
    EXPECT_EQ(storage.num_triangles(), 0u);
    EXPECT_EQ(storage.indices.capacity(), plain.indices.size());
    const float* reserved = storage.positions.data();
    Result<Mesh> filled = build_static_volume(*light, depth, {}, "depth.exr", std::move(storage));
    ASSERT_TRUE(filled.ok());
    EXPECT_EQ(filled->positions.data(), reserved);
    EXPECT_EQ(filled->positions, plain.positions);
    EXPECT_EQ(filled->indices, plain.indices);
    Result<Mesh> too_small = build_static_volume(*light, depth, {}, "depth.exr",
                                                 reserve_static_volume(light->type, 40, 29));
    ASSERT_TRUE(too_small.ok());
    EXPECT_EQ(too_small->positions, plain.positions);
    EXPECT_EQ(too_small->indices, plain.indices);
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
  const Mesh held = unguarded(needle, depth);
  const Status expected = check_representable(held, needle, Space::world, "needle.json");
  ASSERT_FALSE(expected.ok());
  VolumeOptions named;
  named.light_source = "needle.json";
  const Result<Mesh> built = build_static_volume(needle, depth, named, "depth.exr");
  ASSERT_FALSE(built.ok());
  EXPECT_EQ(built.error().message, expected.error().message);
  StaticVolumeStream stream(needle, depth, {}, "depth.exr", "needle.json");
  const Streamed s = collect(stream);
  ASSERT_FALSE(s.status.ok());
  EXPECT_EQ(s.status.error().message, expected.error().message);
  EXPECT_TRUE(s.mesh.indices.empty());
}

// The float32 guard's verdict and message are the same streamed (two passes over the rows, in
// blocks) and held (two passes over the mesh): refusals whose message counts collapsed and turned
// faces, in several blocks of rows, and sound volumes, which both accept. What the guard accepts
// the checks accept; what it refuses they refuse too, but for float steps at the light's own
// position, which the guard judges and the checks (whose tolerance is each face's own) do not.
TEST(StaticVolumeStream, JudgedAsTheHeldVolumeIs) {
  const auto spot = [](const std::string& position, const std::string& fov) {
    return test::light_from_json(R"({"type": "spot", "position": )" + position +
                                 R"(, "direction": [0, -1, 0], "up": [0, 0, -1], "fov_y_deg": )" +
                                 fov + R"(, "near": 1, "far": 20, "depth": "linear"})");
  };
  // A directional light 10^6 behind a volume 1 deep: the checks' rounding is of its position.
  const auto behind = [](const std::string& ortho, const std::string& near) {
    return test::light_from_json(
        R"({"type": "directional", "position": [0, 1e6, 0], "direction": [0, -1, 0],)"
        R"( "up": [0, 0, -1], "ortho": )" +
        ortho + R"(, "near": )" + near + R"(, "far": 1000000.7, "depth": "linear"})");
  };
  struct Case {
    Light light;
    DepthImage depth;
    std::string refusal;  // empty: accepted
    bool checks_refuse = !refusal.empty();
  };
  const Case cases[] = {
      {spot("[1e6, 10, 0]", "60"), occluded(64, 64),
       "240 of 8190 faces collapse to zero area, 0 face the light): key 'position'"},
      {spot("[3e5, 10, 0]", "60"), occluded(1500, 700), "key 'position'"},
      {spot("[0, 10, 0]", "1e-6"), occluded(700, 500), "keys 'near', 'far' and 'fov_y_deg'"},
      // Texels 18 wide, far coarser than a float step at 10^6 (0.12), and grid vertices 0.2 to
      // 0.4 beyond the near plane, which float32 holds to 1e-5 at their coordinates (up to 100):
      // sound, and both accept it. (When the checks' tolerance was that of the light's position,
      // 0.95, these faces counted as lying in the near plane, facing away: both refused it.)
      {behind("[-100, 100, -100, 100]", "999999.7"),
       test::make_depth(
           11, 11, [](int c, int r) { return 0.2f + 0.05f * static_cast<float>((c + r) % 5); }),
       ""},
      // The same light over finer texels (0.04 wide): float steps at the light's position
      // coarser than a sixteenth of a texel, which the guard refuses; the vertices themselves
      // (coordinates up to 10) hold in float32, and the checks accept the volume.
      {behind("[-10, 10, -10, 10]", "999999.3"), thin_wide_box_map(), "keys 'position' and 'near'",
       false},
      {spot("[0, 10, 0]", "60"), occluded(700, 500), ""},
      {thin_wide_box(), thin_wide_box_map(), ""},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(std::to_string(c.depth.width) + "x" + std::to_string(c.depth.height) + " " +
                 c.refusal);
    const Mesh held = unguarded(c.light, c.depth);
    const Status expected = check_representable(held, c.light, Space::world, "l.json");
    const CheckReport report = check_volume_linear(held, &c.light);
    EXPECT_EQ(report.valid(), !c.checks_refuse) << report.first_failure();
    if (c.refusal.empty()) {
      EXPECT_TRUE(expected.ok()) << expected.error().message;
    } else {
      ASSERT_FALSE(expected.ok());
      EXPECT_NE(expected.error().message.find(c.refusal), std::string::npos)
          << expected.error().message;
    }
    StaticVolumeStream stream(c.light, c.depth, {}, "depth.exr", "l.json");
    const Streamed s = collect(stream);
    ASSERT_EQ(s.status.ok(), expected.ok());
    if (expected.ok()) {
      EXPECT_EQ(s.mesh.positions, held.positions);
      continue;
    }
    EXPECT_EQ(s.status.error().message, expected.error().message);
    EXPECT_TRUE(s.mesh.indices.empty());
  }
}

// What the vertices alone decide (coordinates beyond 1e18: ortho ±1e30) the stream refuses after
// its first pass, before handing on any position, with the held volume's message.
TEST(StaticVolumeStream, RefusesBeforeAnyPositionWhenTheVerticesDecide) {
  const Light huge = test::light_from_json(
      R"({"type": "directional", "position": [0, 10, 0], "direction": [0, -1, 0],)"
      R"( "up": [0, 0, -1], "ortho": [-1e30, 1e30, -1e30, 1e30], "near": 0, "far": 20})");
  const DepthImage depth = occluded(300, 200);
  const Status expected = check_representable(unguarded(huge, depth), huge, Space::world, "l.json");
  ASSERT_FALSE(expected.ok());
  EXPECT_NE(expected.error().message.find("l.json: keys 'ortho', 'near' and 'far': the volume "
                                          "reaches coordinate"),
            std::string::npos)
      << expected.error().message;
  StaticVolumeStream stream(huge, depth, {}, "depth.exr", "l.json");
  std::size_t handed_on = 0;
  const Status s = stream.positions([&](const float*, std::size_t n) {
    handed_on += n;
    return true;
  });
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().message, expected.error().message);
  EXPECT_EQ(handed_on, 0u);
}

// A spot light's radial and linear depths of 0, 1e-20 and 1e-39 are before its near plane and go
// on it (docs/design.md §2), static and adaptive: the same volume as half the near distance
// (radial ones were refused as "shorter than the texel ray's distance from the light").
TEST(StaticVolume, SpotDepthsAtZeroAreOnTheNearPlane) {
  for (const std::string encoding : {"radial", "linear"}) {
    const Light light = test::light_from_json(test::spot_json(encoding));
    const auto map = [](float value) {
      DepthImage d = occluded(33, 31);
      for (std::size_t v = 0; v < d.values.size(); v += 3) d.values[v] = value;
      return ShadowMaps::planar(d, "depth.exr");
    };
    std::vector<BuildVolumeOptions> builds(3);
    builds[1].grid = builds[2].grid = VolumeGrid::adaptive;
    builds[1].adaptive.max_error = builds[2].adaptive.max_error = 0.01;
    builds[2].adaptive.tessellation = Tessellation::quadtree;
    for (const BuildVolumeOptions& options : builds) {
      Result<Mesh> expected = build_volume(light, map(0.05f), options);  // near is 0.1
      ASSERT_TRUE(expected.ok()) << expected.error().message;
      for (const float value : {0.0f, 1e-20f, 1e-39f}) {
        SCOPED_TRACE(encoding + ", depth " + std::to_string(value));
        Result<Mesh> mesh = build_volume(light, map(value), options);
        ASSERT_TRUE(mesh.ok()) << mesh.error().message;
        EXPECT_EQ(mesh->positions, expected->positions);
        EXPECT_EQ(mesh->indices, expected->indices);
      }
    }
  }
}

}  // namespace
}  // namespace lightvol
