// The depth pass of `lightvol shadowmap` against exact ray casting, the depth encodings against
// closed forms, map sizes, and volumes built from a real scene's shadow maps against `check`.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/check/check.h>
#include <lightvol/core/check.h>
#include <lightvol/core/mesh.h>
#include <lightvol/depth/cube_faces.h>
#include <lightvol/light/light.h>
#include <lightvol/scene/bvh.h>
#include <lightvol/scene/raycast.h>
#include <lightvol/scene/scene.h>
#include <lightvol/scene/shadowmap.h>
#include <lightvol/volume/omni_volume.h>
#include <lightvol/volume/static_volume.h>

#include "support/gl_test_context.h"
#include "support/test_support.h"

namespace lightvol {
namespace {

// ---- a small scene: a closed room with boxes and a tilted plane ---------------------------------

void add_quad(Mesh* m, Vec3d a, Vec3d b, Vec3d c, Vec3d d) {
  const auto base = static_cast<std::uint32_t>(m->num_vertices());
  for (const Vec3d& p : {a, b, c, d})
    for (int k = 0; k < 3; ++k) m->positions.push_back(static_cast<float>(p[k]));
  for (const std::uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) m->indices.push_back(base + i);
}

void add_box(Mesh* m, Vec3d lo, Vec3d hi) {
  const auto p = [&](int i) {
    return Vec3d{(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z};
  };
  add_quad(m, p(0), p(2), p(3), p(1));  // z = lo
  add_quad(m, p(4), p(5), p(7), p(6));  // z = hi
  add_quad(m, p(0), p(1), p(5), p(4));  // y = lo
  add_quad(m, p(2), p(6), p(7), p(3));  // y = hi
  add_quad(m, p(0), p(4), p(6), p(2));  // x = lo
  add_quad(m, p(1), p(3), p(7), p(5));  // x = hi
}

Mesh small_scene() {
  Mesh m;
  add_box(&m, {-6, 0, -6}, {6, 6, 6});          // the room (seen from inside)
  add_box(&m, {-3, 0, -2.5}, {-1.5, 2.5, -1});  // a tall box
  add_box(&m, {1, 0, 0.5}, {3.2, 1.2, 2.9});    // a low box
  add_box(&m, {-0.4, 0, 2}, {0.4, 3.5, 2.8});   // a column
  add_quad(&m, {0.5, 0.3, -4}, {4.5, 2.1, -4}, {4.5, 3.4, -1.5}, {0.5, 1.6, -1.5});  // tilted
  return m;
}

// ---- comparison ---------------------------------------------------------------------------------

// −z_eye of window depth d (the distance the tolerance is stated in).
double eye_depth(const Light& light, double d) {
  bool ok = false;
  const Mat4d inv = inverse(light.projection, &ok);
  return -inv.transform_point({0, 0, 2 * d - 1}).z;
}

// Stored float window depth: 4 ulps of 1.0 (the float rounding of clip z and w, of their ratio,
// of the rasterizer's interpolation and of the stored value each contribute about one).
constexpr double kWindowTolerance = 4.0 / (1 << 24);
// Window depth in float rounds eye depth by up to ½ ulp(d)·|dz/dd|, i.e. z·(f−n)·z/(f·n)·2⁻²⁴
// relative for a perspective light; 1e-5 covers z/near ≤ ~100 with the rasterizer's own rounding.
constexpr double kTolerance = 1e-5;
// Silhouette texels allowed, as a fraction of all texels (edges pass near a centre rarely).
constexpr double kSilhouetteFraction = 0.01;

struct Agreement {
  int texels = 0, agree = 0, silhouettes = 0, unexplained = 0;
  double max_relative = 0;  // over the agreeing texels that hit something
  double max_window = 0;    // |window depth difference| over the agreeing texels
  std::string first_unexplained;
};

// A texel agrees when both passes miss, or both hit and their eye depths differ by at most
// `tolerance` relatively or their window depths by at most kWindowTolerance (which is what float
// storage can resolve near the light, where the relative bound becomes tighter than an ulp).
// A disagreeing texel is a silhouette texel when a ray through a point within 0.02 texel of its
// centre sees what OpenGL stored: a triangle edge passes that close, and which side of it the
// centre lies on is down to rounding.
Agreement compare(const Bvh& bvh, const Light& light, int w, int h, int face,
                  const std::vector<float>& gl, const std::vector<double>& ray, double tolerance) {
  Agreement a;
  const auto same = [&](double g, double r, double* rel) {
    if (g >= 1.0 || r >= 1.0) return g >= 1.0 && r >= 1.0;
    const double zg = eye_depth(light, g), zr = eye_depth(light, r);
    *rel = std::abs(zg - zr) / zr;
    return *rel <= tolerance || std::abs(g - r) <= kWindowTolerance;
  };
  for (int row = 0; row < h; ++row)
    for (int col = 0; col < w; ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * w + col;
      ++a.texels;
      double rel = 0;
      if (same(gl[i], ray[i], &rel)) {
        ++a.agree;
        a.max_relative = std::max(a.max_relative, rel);
        if (gl[i] < 1.0f) a.max_window = std::max(a.max_window, std::abs(gl[i] - ray[i]));
        continue;
      }
      bool silhouette = false;
      for (const double dx : {-0.02, 0.0, 0.02})
        for (const double dy : {-0.02, 0.0, 0.02}) {
          const double r = raycast_point(bvh, light, w, h, face, col + 0.5 + dx, row + 0.5 + dy);
          double unused = 0;
          silhouette = silhouette || same(gl[i], r, &unused);
        }
      if (silhouette) {
        ++a.silhouettes;
      } else if (a.unexplained++ == 0) {
        char buf[160];
        std::snprintf(buf, sizeof buf, "face %d texel (%d, %d): GL %.9g, ray %.9g", face, col, row,
                      gl[i], ray[i]);
        a.first_unexplained = buf;
      }
    }
  return a;
}

void expect_agreement(const Light& light, int w, int h) {
  const Mesh scene = small_scene();
  const Bvh bvh(scene);
  Result<ShadowMapRenderer> renderer = ShadowMapRenderer::create(scene);
  ASSERT_TRUE(renderer) << renderer.error().message;
  int hits = 0;
  for (int face = 0; face < pass_count(light); ++face) {
    Result<std::vector<float>> gl = renderer->render_window_depth(light, w, h, face);
    ASSERT_TRUE(gl) << gl.error().message;
    ASSERT_EQ(gl->size(), static_cast<std::size_t>(w) * h);
    const std::vector<double> ray = raycast_window_depth(bvh, light, w, h, face);
    const Agreement a = compare(bvh, light, w, h, face, *gl, ray, kTolerance);
    SCOPED_TRACE("face " + std::to_string(face));
    EXPECT_EQ(a.unexplained, 0) << a.first_unexplained;
    EXPECT_LE(a.silhouettes, kSilhouetteFraction * a.texels);
    std::printf(
        "[ depth    ] face %d: %d texels, %d agree (max rel. %.2e, window %.2e), %d silhouette\n",
        face, a.texels, a.agree, a.max_relative, a.max_window, a.silhouettes);
    for (const float d : *gl) hits += d < 1.0f ? 1 : 0;
  }
  EXPECT_GT(hits, 0);  // the pass saw the scene
}

TEST(ShadowMap, SpotMatchesRayCasting) {
  REQUIRE_GL_CONTEXT();
  expect_agreement(test::light_from_json(R"({"type": "spot", "position": [0.3, 5.5, 0.2],
      "direction": [0.1, -1, 0.25], "up": [0, 0, -1], "fov_y_deg": 75, "near": 0.2, "far": 20})"),
                   128, 128);
}

TEST(ShadowMap, SpotWithAspectAndFlipMatchesRayCasting) {
  REQUIRE_GL_CONTEXT();
  const Light light = test::light_from_json(R"({"type": "spot", "position": [-5, 5, 5],
      "direction": [1, -0.8, -1], "up": [0, 1, 0], "fov_y_deg": 50, "aspect": 1.5, "near": 0.5,
      "far": 30, "flip_y": true})");
  Result<MapSize> size = shadow_map_size(light, 120, "spot.json");
  ASSERT_TRUE(size);
  EXPECT_EQ(size->width, 120);
  EXPECT_EQ(size->height, 80);
  expect_agreement(light, size->width, size->height);
}

TEST(ShadowMap, DirectionalMatchesRayCasting) {
  REQUIRE_GL_CONTEXT();
  expect_agreement(test::light_from_json(R"({"type": "directional", "position": [0, 5.9, 0],
      "direction": [0.3, -1, 0.2], "up": [0, 0, -1], "ortho": [-5, 5, -4, 4], "near": 0, "far": 12})"),
                   96, 96);
}

TEST(ShadowMap, OmniFacesMatchRayCasting) {
  REQUIRE_GL_CONTEXT();
  expect_agreement(test::light_from_json(R"({"type": "omni", "position": [0.4, 3.1, -0.3],
      "near": 0.1, "far": 20})"),
                   48, 48);
}

TEST(ShadowMap, FlipYStoresTheBottomRowFirst) {
  REQUIRE_GL_CONTEXT();
  const Mesh scene = small_scene();
  Result<ShadowMapRenderer> renderer = ShadowMapRenderer::create(scene);
  ASSERT_TRUE(renderer);
  const std::string json =
      R"({"type": "spot", "position": [0.3, 5.5, 0.2], "direction": [0.1, -1, 0.25],
      "up": [0, 0, -1], "fov_y_deg": 75, "near": 0.2, "far": 20, "flip_y": )";
  const Light up = test::light_from_json(json + "false}");
  const Light down = test::light_from_json(json + "true}");
  const int w = 40, h = 30;
  Result<std::vector<float>> a = renderer->render_window_depth(up, w, h, 0);
  Result<std::vector<float>> b = renderer->render_window_depth(down, w, h, 0);
  ASSERT_TRUE(a && b);
  int differing_rows = 0;
  for (int row = 0; row < h; ++row) {
    differing_rows +=
        std::equal(a->begin() + row * w, a->begin() + (row + 1) * w, a->begin() + (h - 1 - row) * w)
            ? 0
            : 1;
    for (int col = 0; col < w; ++col)
      ASSERT_EQ((*a)[row * w + col], (*b)[(h - 1 - row) * w + col]) << col << ", " << row;
  }
  EXPECT_GT(differing_rows, 0);  // the image is not symmetric: the test can tell the rows apart
}

// ---- encodings: closed forms on a floor ---------------------------------------------------------

TEST(ShadowMap, LinearAndRadialDepthOfAFloor) {
  REQUIRE_GL_CONTEXT();
  Mesh floor;
  add_quad(&floor, {-50, 0, -50}, {-50, 0, 50}, {50, 0, 50}, {50, 0, -50});
  Result<ShadowMapRenderer> renderer = ShadowMapRenderer::create(floor);
  ASSERT_TRUE(renderer);
  const std::string base = R"({"type": "spot", "position": [0, 4, 0], "direction": [0, -1, 0],
      "up": [0, 0, -1], "fov_y_deg": 60, "near": 0.1, "far": 30, "depth": ")";
  const int n = 32;
  for (const char* encoding : {"window", "linear", "radial"}) {
    SCOPED_TRACE(encoding);
    const Light light = test::light_from_json(base + encoding + "\"}");
    Result<std::vector<DepthImage>> images = renderer->render(light, {n, n});
    ASSERT_TRUE(images);
    ASSERT_EQ(images->size(), 1u);
    const DepthImage& d = (*images)[0];
    ASSERT_EQ(d.width, n);
    ASSERT_EQ(d.height, n);
    const double t = std::tan(std::numbers::pi / 6);
    for (int row = 0; row < n; ++row)
      for (int col = 0; col < n; ++col) {
        // The texel ray (x t, y t, −1) in eye space meets the floor at eye depth 4.
        const double x = (2.0 * (col + 0.5) / n - 1) * t, y = (1 - 2.0 * (row + 0.5) / n) * t;
        const double linear = 4.0, radial = 4.0 * std::sqrt(1 + x * x + y * y);
        const double window = 0.5 + 0.5 * (30.1 / 29.9 - 2 * 30 * 0.1 / (29.9 * 4.0));
        const double expected =
            encoding[0] == 'w' ? window : (encoding[0] == 'l' ? linear : radial);
        ASSERT_NEAR(d.at(col, row), expected, encoding[0] == 'w' ? 2e-7 : 4e-5 * expected)
            << col << ", " << row;
      }
  }
}

TEST(ShadowMap, NothingHitReadsAsTheFarPlane) {
  REQUIRE_GL_CONTEXT();
  Mesh tiny;
  add_quad(&tiny, {-0.5, 0, -0.5}, {-0.5, 0, 0.5}, {0.5, 0, 0.5}, {0.5, 0, -0.5});
  Result<ShadowMapRenderer> renderer = ShadowMapRenderer::create(tiny);
  ASSERT_TRUE(renderer);
  const std::string base = R"({"type": "spot", "position": [0, 4, 0], "direction": [0, -1, 0],
      "up": [0, 0, -1], "fov_y_deg": 60, "near": 0.1, "far": 30, "depth": ")";
  for (const char* encoding : {"window", "linear", "radial"}) {
    SCOPED_TRACE(encoding);
    const Light light = test::light_from_json(base + encoding + "\"}");
    Result<std::vector<DepthImage>> images = renderer->render(light, {16, 16});
    ASSERT_TRUE(images);
    // Corner texel: nothing hit. Its point must be the far plane's.
    const Unprojector u(light, 16, 16, 0, Space::world);
    Vec3d p;
    ASSERT_TRUE(u.point(0, 0, (*images)[0].at(0, 0), &p));
    const Vec3d f = u.far_point(0, 0);
    EXPECT_LT(length(p - f), 1e-4 * length(f));
    // Centre texel: the quad, at eye depth 4.
    ASSERT_TRUE(u.point(8, 8, (*images)[0].at(8, 8), &p));
    EXPECT_NEAR(p.y, 0.0, 1e-4);
  }
}

// ---- sizes --------------------------------------------------------------------------------------

TEST(ShadowMapSize, SpotAspectDirectionalAndOmni) {
  const Light spot = test::light_from_json(test::spot_json("window", 2.0));
  Result<MapSize> s = shadow_map_size(spot, 101, "spot.json");
  ASSERT_TRUE(s);
  EXPECT_EQ(s->width, 101);
  EXPECT_EQ(s->height, 51);  // round(50.5) = 51
  s = shadow_map_size(test::light_from_json(test::directional_json()), 64, "dir.json");
  ASSERT_TRUE(s);
  EXPECT_EQ(s->width, 64);
  EXPECT_EQ(s->height, 64);
  s = shadow_map_size(test::light_from_json(R"({"type": "omni", "position": [0, 1, 0], "near": 0.1,
      "far": 10})"),
                      32, "omni.json");
  ASSERT_TRUE(s);
  EXPECT_EQ(s->width, 32);
  EXPECT_EQ(s->height, 32);
}

TEST(ShadowMapSize, RejectsTooSmallOrTooLarge) {
  const Light spot = test::light_from_json(test::spot_json());
  Result<MapSize> s = shadow_map_size(spot, 1, "spot.json");
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("shadow_map_size(n): must lie in [2, 16384], got 1"),
            std::string::npos)
      << s.error().message;
  EXPECT_FALSE(shadow_map_size(spot, 20000, "spot.json"));
  s = shadow_map_size(test::light_from_json(test::spot_json("window", 10.0)), 8, "wide.json");
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("wide.json: key 'aspect'"), std::string::npos)
      << s.error().message;
}

TEST(Scene, LoadErrorsNameTheFile) {
  Result<Mesh> m = load_scene("/nonexistent/scene.obj");
  ASSERT_FALSE(m);
  EXPECT_NE(m.error().message.find("/nonexistent/scene.obj"), std::string::npos)
      << m.error().message;
  test::TempDir dir;
  const std::string path = dir.write("nan.obj", "v 0 0 0\nv 1 0 0\nv 0 nan 1\nf 1 2 3\n");
  m = load_scene(path);
  ASSERT_FALSE(m);
  EXPECT_NE(m.error().message.find(path), std::string::npos) << m.error().message;
}

// ---- a real scene: Sponza -----------------------------------------------------------------------

std::string sponza_path() {
  return std::string(LIGHTVOL_SOURCE_DIR) + "/../shared/scenes/sponza/sponza.obj";
}

#define REQUIRE_SPONZA()                               \
  if (!std::filesystem::exists(sponza_path()))         \
  GTEST_SKIP() << "Sponza is not at " << sponza_path() \
               << " (the Dabrovic Sponza OBJ; data/README.md says where it comes from)"

const Mesh& sponza() {
  static const Mesh mesh = [] {
    Result<Mesh> m = load_scene(sponza_path());
    LV_CHECK(m.ok());
    return std::move(*m);
  }();
  return mesh;
}

void expect_valid(const Mesh& volume, const Light& light, bool cgal) {
  EXPECT_TRUE(test::is_closed_and_oriented(volume));
  CheckOptions options;
  options.cgal_with_light = cgal;
  const CheckReport report = check_volume(volume, &light, options);
  EXPECT_TRUE(report.valid()) << report.first_failure();
  EXPECT_GT(report.volume, 0);
}

TEST(Sponza, SpotAndDirectionalVolumesPassCheck) {
  REQUIRE_GL_CONTEXT();
  REQUIRE_SPONZA();
  const Mesh& scene = sponza();
  ASSERT_EQ(scene.num_triangles(), 66454u);
  Result<ShadowMapRenderer> renderer = ShadowMapRenderer::create(scene);
  ASSERT_TRUE(renderer);
  for (const char* json :
       {R"({"type": "spot", "position": [0, 14, 0], "direction": [0.05, -1, 0.1], "up": [1, 0, 0],
            "fov_y_deg": 70, "near": 0.5, "far": 40})",
        R"({"type": "spot", "position": [-10, 10, 6], "direction": [12, -10, -8], "up": [0, 1, 0],
            "fov_y_deg": 60, "aspect": 1.5, "near": 0.5, "far": 50, "depth": "linear"})",
        R"({"type": "directional", "position": [0, 18, 0], "direction": [0.2, -1, 0.1],
            "up": [1, 0, 0], "ortho": [-18, 18, -9, 9], "near": 0, "far": 30})"}) {
    const Light light = test::light_from_json(json);
    Result<MapSize> size = shadow_map_size(light, 64, "light.json");
    ASSERT_TRUE(size);
    Result<std::vector<DepthImage>> depth = renderer->render(light, *size);
    ASSERT_TRUE(depth);
    int hits = 0, misses = 0;
    for (const float d : (*depth)[0].values)
      (d < (light.depth == DepthEncoding::window ? 1.0f : 39.9f) ? hits : misses)++;
    EXPECT_GT(hits, 0);
    Result<Mesh> volume = build_static_volume(light, (*depth)[0], {}, "sponza");
    ASSERT_TRUE(volume) << volume.error().message;
    EXPECT_EQ(volume->num_triangles(),
              static_volume_counts(light.type, size->width, size->height).triangles);
    expect_valid(*volume, light, /*cgal=*/true);
  }
}

TEST(Sponza, OmniVolumePassesCheck) {
  REQUIRE_GL_CONTEXT();
  REQUIRE_SPONZA();
  Result<ShadowMapRenderer> renderer = ShadowMapRenderer::create(sponza());
  ASSERT_TRUE(renderer);
  const Light light = test::light_from_json(R"({"type": "omni", "position": [0, 6, 0], "near": 0.1,
      "far": 40})");
  Result<std::vector<DepthImage>> depth = renderer->render(light, {32, 32});
  ASSERT_TRUE(depth);
  ASSERT_EQ(depth->size(), 6u);
  CubeFaces cube;
  for (int f = 0; f < kOmniFaces; ++f) {
    cube.faces[f] = (*depth)[f];
    cube.sources[f] = "sponza " + omni_face_name(f);
  }
  Result<Mesh> volume = build_omni_volume(light, cube, {});
  ASSERT_TRUE(volume) << volume.error().message;
  EXPECT_EQ(volume->num_triangles(), 12u * 32 * 32 - 4);
  expect_valid(*volume, light, /*cgal=*/true);
}

TEST(Sponza, GlAgreesWithRayCastingOnTheRealScene) {
  REQUIRE_GL_CONTEXT();
  REQUIRE_SPONZA();
  const Light light = test::light_from_json(R"({"type": "spot", "position": [0, 14, 0],
      "direction": [0.05, -1, 0.1], "up": [1, 0, 0], "fov_y_deg": 70, "near": 0.5, "far": 40})");
  const Bvh bvh(sponza());
  Result<ShadowMapRenderer> renderer = ShadowMapRenderer::create(sponza());
  ASSERT_TRUE(renderer);
  const int n = 64;
  Result<std::vector<float>> gl = renderer->render_window_depth(light, n, n, 0);
  ASSERT_TRUE(gl);
  const Agreement a =
      compare(bvh, light, n, n, 0, *gl, raycast_window_depth(bvh, light, n, n, 0), kTolerance);
  EXPECT_EQ(a.unexplained, 0) << a.first_unexplained;
  EXPECT_LE(a.silhouettes, kSilhouetteFraction * a.texels);
  std::printf(
      "[ depth    ] sponza: %d texels, %d agree (max rel. %.2e, window %.2e), %d silhouette\n",
      a.texels, a.agree, a.max_relative, a.max_window, a.silhouettes);
}

}  // namespace
}  // namespace lightvol
