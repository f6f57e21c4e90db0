// The live volume (render/live_volume.h): the static volume made on the GPU from a shadow map
// texture is build's, vertex for vertex, and draws build's airlight; a map that changes between
// frames changes it; bad textures are refused with a message.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/depth/cube_faces.h>
#include <lightvol/render/gl_volume.h>
#include <lightvol/render/live_volume.h>
#include <lightvol/volume/adaptive_volume.h>
#include <lightvol/volume/omni_volume.h>
#include <lightvol/volume/static_volume.h>

#include "support/analytic_scene.h"
#include "support/gl_test_context.h"
#include "support/test_support.h"

namespace lightvol {
namespace {

using namespace gl;

// The light of `json_linear` (a "linear" light) with depth encoding `encoding` and flip_y.
Light with_encoding(const std::string& json_linear, DepthEncoding encoding, bool flip_y) {
  Light light = test::light_from_json(json_linear);
  light.depth = encoding;
  light.flip_y = flip_y;
  return light;
}

// The analytic scene's W×H map of `light` (omni: of face `face`) in its encoding (computed in
// double from the linear map, rounded to float as a depth pass would store it).
DepthImage scene_map(const Light& light, int width, int height, const test::Box& box = {},
                     int face = 0) {
  Light linear = light;
  linear.depth = DepthEncoding::linear;
  DepthImage map = test::scene_shadow_map(linear, width, height, box, face);
  if (light.depth == DepthEncoding::linear) return map;
  const Unprojector world(linear, width, height, face, Space::world);
  const Mat4d view = light.type == LightType::omni ? omni_face_view(light, face) : light.view;
  for (int row = 0; row < height; ++row)
    for (int col = 0; col < width; ++col) {
      float& d = map.values[static_cast<std::size_t>(row) * width + col];
      Vec3d q;
      EXPECT_TRUE(world.point(col, row, d, &q));
      const Vec3d p = view.transform_point(q);
      if (light.depth == DepthEncoding::radial) {
        d = static_cast<float>(length(p));
      } else {
        const Vec3d ndc = light.projection.transform_point(p);
        d = static_cast<float>(std::clamp(0.5 * ndc.z + 0.5, 0.0, 1.0));
      }
    }
  return map;
}

// The largest |coordinate| of `mesh` and of the light's position: the scale of the rounding.
double coordinate_scale(const Mesh& mesh, const Light& light) {
  double scale = std::max(
      {std::abs(light.position.x), std::abs(light.position.y), std::abs(light.position.z)});
  for (float x : mesh.positions) scale = std::max(scale, static_cast<double>(std::abs(x)));
  return scale;
}

// The largest |GPU − build| over all coordinates, relative to coordinate_scale.
double largest_difference(const std::vector<float>& gpu, const Mesh& mesh, const Light& light) {
  EXPECT_EQ(gpu.size(), mesh.positions.size());
  double worst = 0;
  for (std::size_t i = 0; i < std::min(gpu.size(), mesh.positions.size()); ++i)
    worst = std::max(worst, std::abs(static_cast<double>(gpu[i]) - mesh.positions[i]));
  return worst / coordinate_scale(mesh, light);
}

// Float rounding: each vertex is a convex blend of its ray's near and far points moved by a float
// matrix; every step rounds relative to the coordinates it combines (live_volume.h). A few tens
// of float ulps (6e-8 each) of the scale: 1e-5 leaves two orders of magnitude.
constexpr double kPositionTolerance = 2e-6;

// A box off the light's axis in both directions across it: a map flipped in rows or columns is
// another map.
const test::Box kOffAxisBox{{-0.7, 1.0, -0.9}, {0.2, 1.5, 0.1}};

struct MapCase {
  const char* name;
  std::string json;  // a "linear" light
  DepthEncoding encoding;
  bool flip_y;
  int width, height;
};

std::vector<MapCase> map_cases() {
  std::vector<MapCase> cases;
  for (DepthEncoding e : {DepthEncoding::window, DepthEncoding::linear, DepthEncoding::radial}) {
    cases.push_back({"spot 64x64", test::spot_json("linear"), e, false, 64, 64});
    cases.push_back({"spot 96x40 flip_y", test::spot_json("linear", 96.0 / 40), e, true, 96, 40});
    cases.push_back({"spot 33x71", test::spot_json("linear", 33.0 / 71), e, false, 33, 71});
    cases.push_back({"directional 64x64", test::directional_json("linear"), e, false, 64, 64});
    cases.push_back(
        {"directional 50x128 flip_y", test::directional_json("linear"), e, true, 50, 128});
  }
  return cases;
}

TEST(LiveVolume, TrianglesAreBuildsInBuildsOrder) {
  for (const MapCase& c : map_cases()) {
    const Light light = with_encoding(c.json, c.encoding, c.flip_y);
    const DepthImage map = scene_map(light, c.width, c.height);
    Result<Mesh> built = build_static_volume(light, map, {}, "map");
    ASSERT_TRUE(built) << built.error().message;
    EXPECT_EQ(static_volume_indices(light, c.width, c.height), built->indices) << c.name;
  }
}

TEST(LiveVolume, VerticesAreBuildsToFloatRounding) {
  REQUIRE_GL_CONTEXT();
  for (const MapCase& c : map_cases()) {
    const Light light = with_encoding(c.json, c.encoding, c.flip_y);
    const DepthImage map = scene_map(light, c.width, c.height, kOffAxisBox);
    Result<Mesh> built = build_static_volume(light, map, {}, "map");
    ASSERT_TRUE(built) << built.error().message;
    const TextureHandle texture = upload_shadow_map(light, map);
    Result<std::unique_ptr<LiveVolume>> live =
        LiveVolume::create(light, {texture.id(), c.width, c.height});
    ASSERT_TRUE(live) << live.error().message;
    EXPECT_EQ((*live)->num_vertices(), built->num_vertices());
    EXPECT_EQ((*live)->num_triangles(), built->num_triangles());
    Result<std::vector<float>> gpu = (*live)->read_positions();
    ASSERT_TRUE(gpu) << gpu.error().message;
    const double worst = largest_difference(*gpu, *built, light);
    std::printf("  %-26s %-6s largest difference %.2e of the scale\n", c.name,
                std::string(to_string(c.encoding)).c_str(), worst);
    EXPECT_LE(worst, kPositionTolerance) << c.name << " " << to_string(c.encoding);
  }
}

// An omni light off the box's axes, its six faces.
const char kOmniJson[] =
    R"({"type": "omni", "position": [0.3, 2.5, 0.2], "near": 0.1, "far": 30, "depth": "linear"})";

CubeFaces omni_maps(const Light& light, int width) {
  CubeFaces cube;
  for (int f = 0; f < kOmniFaces; ++f) {
    cube.faces[f] = scene_map(light, width, width, kOffAxisBox, f);
    cube.sources[f] = omni_face_name(f);
  }
  return cube;
}

TEST(LiveVolume, OmniVerticesAndTrianglesAreBuilds) {
  REQUIRE_GL_CONTEXT();
  for (DepthEncoding e : {DepthEncoding::window, DepthEncoding::linear, DepthEncoding::radial})
    for (const auto& [width, flip_y] : {std::pair{32, false}, std::pair{48, true}}) {
      const Light light = with_encoding(kOmniJson, e, flip_y);
      const CubeFaces cube = omni_maps(light, width);
      Result<Mesh> built = build_omni_volume(light, cube, {});
      ASSERT_TRUE(built) << built.error().message;
      EXPECT_EQ(omni_volume_indices(light, width), built->indices);
      std::vector<TextureHandle> textures;
      std::vector<GlShadowMap> maps;
      for (const DepthImage& face : cube.faces) {
        textures.push_back(upload_shadow_map(light, face));
        maps.push_back({textures.back().id(), width, width});
      }
      Result<std::unique_ptr<LiveVolume>> live = LiveVolume::create(light, maps);
      ASSERT_TRUE(live) << live.error().message;
      EXPECT_EQ((*live)->num_vertices(), built->num_vertices());
      EXPECT_EQ((*live)->num_triangles(), built->num_triangles());
      Result<std::vector<float>> gpu = (*live)->read_positions();
      ASSERT_TRUE(gpu) << gpu.error().message;
      const double worst = largest_difference(*gpu, *built, light);
      std::printf("  omni %dx%d%s %-6s largest difference %.2e of the scale\n", width, width,
                  flip_y ? " flip_y" : "", std::string(to_string(e)).c_str(), worst);
      EXPECT_LE(worst, kPositionTolerance) << width << " " << to_string(e);
    }
}

TEST(LiveVolume, ADepthTextureGivesTheSameVertices) {
  REQUIRE_GL_CONTEXT();
  for (const char* json : {"spot", "directional"}) {
    const std::string linear =
        std::string(json) == "spot" ? test::spot_json("linear") : test::directional_json("linear");
    const Light light = with_encoding(linear, DepthEncoding::window, false);
    const DepthImage map = scene_map(light, 48, 48, kOffAxisBox);
    std::vector<float> gl_rows(map.values.size());
    for (int t = 0; t < 48; ++t)
      std::copy_n(map.values.begin() + (47 - t) * 48, 48, gl_rows.begin() + t * 48);
    const TextureHandle texture = make_texture_2d(48, 48, GL_DEPTH_COMPONENT32F, gl_rows.data(), 1);
    Result<std::unique_ptr<LiveVolume>> live = LiveVolume::create(light, {texture.id(), 48, 48});
    ASSERT_TRUE(live) << live.error().message;
    Result<Mesh> built = build_static_volume(light, map, {}, "map");
    ASSERT_TRUE(built) << built.error().message;
    Result<std::vector<float>> gpu = (*live)->read_positions();
    ASSERT_TRUE(gpu) << gpu.error().message;
    EXPECT_LE(largest_difference(*gpu, *built, light), kPositionTolerance) << json;
  }
}

// The render tests' medium and cameras (tests/render/gl_volume_test.cpp).
constexpr int kImageW = 64, kImageH = 48;

// The airlight of `renderer` drawing build's mesh of `map`.
Image mesh_image(GlVolumeRenderer& renderer, const Light& light, const DepthImage& map) {
  Result<Mesh> built = build_static_volume(light, map, {}, "map");
  EXPECT_TRUE(built) << built.error().message;
  renderer.set_volume(*built);
  return renderer.render();
}

// Live against mesh: the same vertices to float rounding, drawn by the same passes; a pixel whose
// coverage a rounding flips moves the sum by one fragment's share. Measured: relative L2 below
// 1e-6 and zero for most cases; 1e-4 is what they may differ by.
constexpr double kImageTolerance = 1e-4;

TEST(LiveVolume, DrawsTheAirlightOfBuildsMesh) {
  REQUIRE_GL_CONTEXT();
  const std::vector<test::LightViewCase> cases = test::light_view_cases();
  for (const test::LightViewCase& c : cases) {
    const Light light = with_encoding(c.json, c.encoding, false);
    const DepthImage map = scene_map(light, 80, 64, kOffAxisBox);
    const RenderScene scene =
        test::make_render_scene(test::make_camera(c.eye, c.target, kImageW, kImageH), light,
                                test::render_test_medium(), kOffAxisBox);
    Result<std::unique_ptr<GlVolumeRenderer>> renderer = GlVolumeRenderer::create(scene);
    ASSERT_TRUE(renderer) << renderer.error().message;
    const Image expected = mesh_image(**renderer, light, map);
    const TextureHandle texture = upload_shadow_map(light, map);
    Result<std::unique_ptr<LiveVolume>> live = LiveVolume::create(light, {texture.id(), 80, 64});
    ASSERT_TRUE(live) << live.error().message;
    double total = 0;
    for (double v : expected.values) total += v;
    EXPECT_GT(total, 0) << c.name;
    for (LiveDraw draw : {LiveDraw::vertex_stage, LiveDraw::two_pass}) {
      ASSERT_TRUE((*renderer)->set_volume(**live, draw));
      const ImageDifference d = compare_images((*renderer)->render(), expected);
      std::printf("  %-28s %-12s relative L2 %.2e  max abs %.2e\n", c.name,
                  draw == LiveDraw::two_pass ? "two passes" : "vertex stage", d.relative_l2,
                  d.max_abs);
      EXPECT_LE(d.relative_l2, kImageTolerance) << c.name;
    }
  }
}

TEST(LiveVolume, DrawsTheAirlightOfBuildsOmniMesh) {
  REQUIRE_GL_CONTEXT();
  const Light light = with_encoding(kOmniJson, DepthEncoding::window, false);
  const CubeFaces cube = omni_maps(light, 48);
  Result<Mesh> built = build_omni_volume(light, cube, {});
  ASSERT_TRUE(built) << built.error().message;
  std::vector<TextureHandle> textures;
  std::vector<GlShadowMap> maps;
  for (const DepthImage& face : cube.faces) {
    textures.push_back(upload_shadow_map(light, face));
    maps.push_back({textures.back().id(), 48, 48});
  }
  Result<std::unique_ptr<LiveVolume>> live = LiveVolume::create(light, maps);
  ASSERT_TRUE(live) << live.error().message;
  // Outside the lit space's walls; then inside the box's shadow, looking out of it.
  for (auto [eye, target] :
       {std::pair<Vec3d, Vec3d>{{5, 3, 5}, {0, 1, 0}}, {{0.3, 0.5, 0.2}, {3, 0.9, 1}}}) {
    const RenderScene scene =
        test::make_render_scene(test::make_camera(eye, target, kImageW, kImageH), light,
                                test::render_test_medium(), kOffAxisBox);
    Result<std::unique_ptr<GlVolumeRenderer>> renderer = GlVolumeRenderer::create(scene);
    ASSERT_TRUE(renderer) << renderer.error().message;
    (*renderer)->set_volume(*built);
    const Image expected = (*renderer)->render();
    ASSERT_TRUE((*renderer)->set_volume(**live));
    const ImageDifference d = compare_images((*renderer)->render(), expected);
    double total = 0;
    for (double v : expected.values) total += v;
    std::printf("  omni eye (%g, %g, %g): relative L2 %.2e  max abs %.2e\n", eye.x, eye.y, eye.z,
                d.relative_l2, d.max_abs);
    EXPECT_GT(total, 0);
    EXPECT_LE(d.relative_l2, kImageTolerance);
  }
}

TEST(LiveVolume, FollowsTheMapWhenItChangesBetweenFrames) {
  REQUIRE_GL_CONTEXT();
  constexpr int kMap = 64;
  const Light light = with_encoding(test::spot_json("linear"), DepthEncoding::window, false);
  // The box moves 0.8 along x between the two frames.
  const test::Box first{{-0.9, 1.0, -0.5}, {0.1, 1.5, 0.5}};
  const test::Box second{{-0.1, 1.0, -0.5}, {0.9, 1.5, 0.5}};
  const DepthImage map1 = scene_map(light, kMap, kMap, first);
  const DepthImage map2 = scene_map(light, kMap, kMap, second);
  const RenderScene scene = test::make_render_scene(
      test::make_camera({6, 3, 6}, {0, 1, 0}, kImageW, kImageH), light, test::render_test_medium());
  Result<std::unique_ptr<GlVolumeRenderer>> renderer = GlVolumeRenderer::create(scene);
  ASSERT_TRUE(renderer) << renderer.error().message;
  const Image expected1 = mesh_image(**renderer, light, map1);
  const Image expected2 = mesh_image(**renderer, light, map2);

  const TextureHandle texture = upload_shadow_map(light, map1);
  Result<std::unique_ptr<LiveVolume>> live = LiveVolume::create(light, {texture.id(), kMap, kMap});
  ASSERT_TRUE(live) << live.error().message;
  ASSERT_TRUE((*renderer)->set_volume(**live, LiveDraw::vertex_stage));
  const Image frame1 = (*renderer)->render();
  ASSERT_TRUE((*renderer)->set_volume(**live, LiveDraw::two_pass));
  const Image frame1_two_pass = (*renderer)->render();
  // The next frame's depth pass writes into the same texture (here: an upload of the new map).
  std::vector<float> rows(static_cast<std::size_t>(kMap) * kMap);
  for (int t = 0; t < kMap; ++t)
    std::copy_n(map2.values.begin() + (kMap - 1 - t) * kMap, kMap, rows.begin() + t * kMap);
  glBindTexture(GL_TEXTURE_2D, texture.id());
  glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, kMap, kMap, GL_RED, GL_FLOAT, rows.data());
  glBindTexture(GL_TEXTURE_2D, 0);
  const Image frame2_two_pass = (*renderer)->render();
  ASSERT_TRUE((*renderer)->set_volume(**live, LiveDraw::vertex_stage));
  const Image frame2 = (*renderer)->render();

  const ImageDifference d1 = compare_images(frame1, expected1);
  const ImageDifference d2 = compare_images(frame2, expected2);
  const ImageDifference moved = compare_images(frame2, frame1);
  std::printf("  frame 1 against build: %.2e; frame 2: %.2e; frame 2 against frame 1: %.2e\n",
              d1.relative_l2, d2.relative_l2, moved.relative_l2);
  EXPECT_LE(d1.relative_l2, kImageTolerance);
  EXPECT_LE(d2.relative_l2, kImageTolerance);
  EXPECT_LE(compare_images(frame1_two_pass, expected1).relative_l2, kImageTolerance);
  EXPECT_LE(compare_images(frame2_two_pass, expected2).relative_l2, kImageTolerance);
  EXPECT_GT(moved.relative_l2, 100 * kImageTolerance);  // the shaft moved

  Result<Mesh> built2 = build_static_volume(light, map2, {}, "map");
  ASSERT_TRUE(built2) << built2.error().message;
  Result<std::vector<float>> gpu = (*live)->read_positions();
  ASSERT_TRUE(gpu) << gpu.error().message;
  EXPECT_LE(largest_difference(*gpu, *built2, light), kPositionTolerance);
}

TEST(LiveVolume, RefusesTexturesItCannotRead) {
  REQUIRE_GL_CONTEXT();
  const Light window = with_encoding(test::spot_json("linear"), DepthEncoding::window, false);
  const Light linear = with_encoding(test::spot_json("linear"), DepthEncoding::linear, false);
  const std::vector<float> zeros(4 * 32 * 16, 0.5f);
  const TextureHandle r32f = make_texture_2d(32, 16, GL_R32F, zeros.data(), 1);
  const TextureHandle rgba = make_texture_2d(32, 16, GL_RGBA32F, zeros.data(), 4);
  const TextureHandle depth = make_texture_2d(32, 16, GL_DEPTH_COMPONENT32F, zeros.data(), 1);
  const TextureHandle depth16 = make_texture_2d(16, 16, GL_R32F, zeros.data(), 1);
  const std::string r32f_name = "shadow map texture " + std::to_string(r32f.id());
  const auto error = [](const Light& light, const std::vector<GlShadowMap>& maps) {
    Result<std::unique_ptr<LiveVolume>> live = LiveVolume::create(light, maps);
    return live ? std::string("accepted") : live.error().message;
  };
  EXPECT_EQ(error(window, {{r32f.id(), 32, 32}}),
            r32f_name + ": level 0 is 32x16, not the 32x32 given");
  EXPECT_EQ(error(window, {{r32f.id(), 1, 16}}),
            r32f_name + ": size 1x16 given; a volume needs at least 2x2 texels");
  EXPECT_EQ(error(window, {{rgba.id(), 32, 16}}),
            "shadow map texture " + std::to_string(rgba.id()) +
                ": internal format 0x8814 is neither a depth format nor GL_R32F");
  EXPECT_EQ(error(linear, {{depth.id(), 32, 16}}),
            "shadow map texture " + std::to_string(depth.id()) +
                ": a depth texture holds window depth in [0, 1]; the light's \"depth\" is "
                "\"linear\", which needs a GL_R32F texture");
  EXPECT_EQ(error(window, {{987654, 32, 16}}), "shadow map texture 987654: not a texture name");
  glBindTexture(GL_TEXTURE_2D, depth.id());
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
  glBindTexture(GL_TEXTURE_2D, 0);
  EXPECT_EQ(error(window, {{depth.id(), 32, 16}}),
            "shadow map texture " + std::to_string(depth.id()) +
                ": GL_TEXTURE_COMPARE_MODE is on; texelFetch needs it GL_NONE");
  Light omni = test::light_from_json(
      R"({"type": "omni", "position": [0, 2, 0], "near": 0.1, "far": 30, "depth": "linear"})");
  EXPECT_EQ(error(omni, {{r32f.id(), 32, 16}}),
            "live volume: omni lights need 6 shadow maps (their cube faces), got 1");
  EXPECT_EQ(error(window, std::vector<GlShadowMap>(6, {r32f.id(), 32, 16})),
            "live volume: spot lights need 1 shadow map, got 6");
  std::vector<GlShadowMap> faces(6, {depth16.id(), 16, 16});
  faces[3] = {r32f.id(), 32, 16};
  EXPECT_EQ(error(omni, faces),
            r32f_name +
                " (face -Y (ny)): 32x16; omni faces are square and all of one size (face "
                "+X (px) is 16x16)");
  // A good texture after all that: no GL error left behind.
  EXPECT_EQ(error(window, {{r32f.id(), 32, 16}}), "accepted");
  EXPECT_EQ(pending_error(), "");
}

// An engine's surface texture (GlVolumeRenderer::set_surface) stands for the scene's distances:
// the same texture as the renderer's own gives the same image, a surface moved nearer changes
// it, 0 goes back; textures it cannot read are refused naming them, keeping what it had.
TEST(LiveVolume, ReadsTheSurfaceFromAnEnginesTexture) {
  REQUIRE_GL_CONTEXT();
  const Light light = with_encoding(test::spot_json("linear"), DepthEncoding::window, false);
  const DepthImage map = scene_map(light, 64, 64, kOffAxisBox);
  const RenderScene scene =
      test::make_render_scene(test::make_camera({6, 3, 6}, {0, 1, 0}, kImageW, kImageH), light,
                              test::render_test_medium(), kOffAxisBox);
  Result<std::unique_ptr<GlVolumeRenderer>> renderer = GlVolumeRenderer::create(scene);
  ASSERT_TRUE(renderer) << renderer.error().message;
  const Image own = mesh_image(**renderer, light, map);
  const TextureHandle same = make_surface_texture(scene);
  ASSERT_TRUE((*renderer)->set_surface(same.id()));
  EXPECT_EQ((*renderer)->render().values, own.values);
  RenderScene nearer = scene;
  for (double& t : nearer.surface) t = std::min(t, 5.0);
  const TextureHandle near_texture = make_surface_texture(nearer);
  ASSERT_TRUE((*renderer)->set_surface(near_texture.id()));
  EXPECT_GT(compare_images((*renderer)->render(), own).relative_l2, 0.01);

  const std::vector<float> values(4 * kImageW * kImageH, 1.0f);
  const TextureHandle small = make_texture_2d(kImageW, kImageH - 1, GL_R32F, values.data(), 1);
  const TextureHandle rg = make_texture_2d(kImageW, kImageH, GL_RG32F, values.data(), 2);
  const auto error = [&](GLuint texture) {
    Status s = (*renderer)->set_surface(texture);
    return s ? std::string("accepted") : s.error().message;
  };
  EXPECT_EQ(error(small.id()), "surface texture " + std::to_string(small.id()) +
                                   ": level 0 is 64x47, the camera 64x48");
  EXPECT_EQ(error(rg.id()), "surface texture " + std::to_string(rg.id()) +
                                ": internal format 0x8230 is not GL_R32F");
  EXPECT_EQ(error(987654), "surface texture 987654: not a texture name");
  EXPECT_EQ(pending_error(), "");
  // Still the nearer surface after the refusals; 0 goes back to the scene's own.
  EXPECT_GT(compare_images((*renderer)->render(), own).relative_l2, 0.01);
  ASSERT_TRUE((*renderer)->set_surface(0));
  EXPECT_EQ((*renderer)->render().values, own.values);
}

// A mesh's triangles as a sorted list, each rotated to start at its smallest index.
std::vector<std::array<std::uint32_t, 3>> sorted_triangles(const Mesh& mesh) {
  std::vector<std::array<std::uint32_t, 3>> out;
  for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
    std::array<std::uint32_t, 3> a = {mesh.indices[3 * t], mesh.indices[3 * t + 1],
                                      mesh.indices[3 * t + 2]};
    std::rotate(a.begin(), std::min_element(a.begin(), a.end()), a.end());
    out.push_back(a);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// NaN texels (which build refuses): the frame goes on, the texel's vertex on its near plane
// (build's vertex of that texel at the near depth), no GL error; validate() names the texture and
// the pixel, and passes again once the map is good. A texture reallocated at another size since
// create is named too. The adaptive live volume (window and linear depth) reads the NaN texel as
// its near depth too: build's quadtree of that map.
TEST(LiveVolume, ANanTexelGoesToTheNearPlaneAndValidateNamesIt) {
  REQUIRE_GL_CONTEXT();
  for (DepthEncoding e : {DepthEncoding::window, DepthEncoding::linear, DepthEncoding::radial}) {
    const Light light = with_encoding(test::spot_json("linear"), e, false);
    DepthImage map = scene_map(light, 32, 24, kOffAxisBox);
    const TextureHandle texture = upload_shadow_map(light, map);
    Result<std::unique_ptr<LiveVolume>> live = LiveVolume::create(light, {texture.id(), 32, 24});
    ASSERT_TRUE(live) << live.error().message;
    EXPECT_TRUE((*live)->validate());
    const std::string name = "shadow map texture " + std::to_string(texture.id());

    // Pixel (5, 7) of the image becomes NaN: GL row 24 - 1 - 7.
    DepthImage nan_map = map;
    nan_map.values[7 * 32 + 5] = std::numeric_limits<float>::quiet_NaN();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    glBindTexture(GL_TEXTURE_2D, texture.id());
    glTexSubImage2D(GL_TEXTURE_2D, 0, 5, 24 - 1 - 7, 1, 1, GL_RED, GL_FLOAT, &nan);
    glBindTexture(GL_TEXTURE_2D, 0);
    const Status checked = (*live)->validate();
    ASSERT_FALSE(checked) << to_string(e);
    EXPECT_EQ(checked.error().message.rfind(name + ": pixel (5, 7): depth is NaN (", 0), 0u)
        << checked.error().message;
    Result<std::vector<float>> gpu = (*live)->read_positions();
    ASSERT_TRUE(gpu) << gpu.error().message;
    DepthImage near_map = map;
    near_map.values[7 * 32 + 5] =
        e == DepthEncoding::window ? 0.0f : static_cast<float>(light.near);
    Result<Mesh> built = build_static_volume(light, near_map, {}, "map");
    ASSERT_TRUE(built) << built.error().message;
    EXPECT_LE(largest_difference(*gpu, *built, light), kPositionTolerance) << to_string(e);
    EXPECT_EQ(pending_error(), "");
    if (e != DepthEncoding::radial) {
      LiveOptions options;
      options.max_error = 0.01;
      Result<std::unique_ptr<LiveVolume>> adaptive =
          LiveVolume::create(light, {texture.id(), 32, 24}, options);
      ASSERT_TRUE(adaptive) << adaptive.error().message;
      Result<LiveMesh> mesh = (*adaptive)->read_mesh();
      ASSERT_TRUE(mesh) << mesh.error().message;
      AdaptiveOptions quadtree;
      quadtree.tessellation = Tessellation::quadtree;
      quadtree.max_error = 0.01;
      Result<Mesh> cpu = build_adaptive_volume(light, near_map, {}, quadtree, "map");
      ASSERT_TRUE(cpu) << cpu.error().message;
      EXPECT_TRUE(mesh->converged) << to_string(e);
      EXPECT_TRUE(sorted_triangles(mesh->mesh) == sorted_triangles(*cpu)) << to_string(e);
      EXPECT_EQ(pending_error(), "");
    }

    // The next frame's map is good again.
    glBindTexture(GL_TEXTURE_2D, texture.id());
    glTexSubImage2D(GL_TEXTURE_2D, 0, 5, 24 - 1 - 7, 1, 1, GL_RED, GL_FLOAT,
                    &map.values[7 * 32 + 5]);
    EXPECT_TRUE((*live)->validate()) << to_string(e);
    // The engine reallocates its texture at another size without telling the live volume.
    glBindTexture(GL_TEXTURE_2D, texture.id());
    glTexImage2D(GL_TEXTURE_2D, 0, GL_R32F, 16, 16, 0, GL_RED, GL_FLOAT, nullptr);
    glBindTexture(GL_TEXTURE_2D, 0);
    const Status resized = (*live)->validate();
    ASSERT_FALSE(resized);
    EXPECT_EQ(resized.error().message, name + ": level 0 is 16x16, not the 32x24 given");
    EXPECT_EQ(pending_error(), "");
  }
}

}  // namespace
}  // namespace lightvol
