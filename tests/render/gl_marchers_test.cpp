// Ray marching converges to the volume's exact airlight as the step count grows; interleaved
// sampling with the gather helps at a fixed count; omni maps work; the radial blur is finite.
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include <lightvol/depth/cube_faces.h>
#include <lightvol/render/gl_marchers.h>
#include <lightvol/render/reference.h>
#include <lightvol/volume/omni_volume.h>
#include <lightvol/volume/static_volume.h>

#include "support/analytic_scene.h"
#include "support/gl_test_context.h"
#include "support/test_support.h"

namespace lightvol {
namespace {

constexpr int kMap = 96, kW = 64, kH = 48;

Medium medium() {
  Medium m;
  m.scattering = 0.06;
  m.absorption = 0.02;
  m.intensity = 20;
  m.phase = {PhaseType::hg, 0.3, 0};
  return m;
}

// The gather of the marcher on the CPU: an M-wide box, horizontal then vertical, clamped at
// borders.
Image box_gather(const Image& in, int m) {
  Image out = in;
  for (int pass = 0; pass < 2; ++pass) {
    const Image src = out;
    for (int row = 0; row < in.height; ++row)
      for (int col = 0; col < in.width; ++col) {
        double sum = 0;
        int n = 0;
        for (int k = -(m - 1) / 2; k <= m / 2; ++k) {
          const int c = pass == 0 ? col + k : col, r = pass == 0 ? row : row - k;
          if (c < 0 || r < 0 || c >= in.width || r >= in.height) continue;
          sum += src.at(c, r);
          ++n;
        }
        out.values[static_cast<std::size_t>(row) * in.width + col] = sum / n;
      }
  }
  return out;
}

Image march(const RenderScene& scene, const DepthImage& map, MarchOptions o) {
  Result<std::unique_ptr<GlMarcher>> m = GlMarcher::create(scene, {map}, {"shadow"}, o);
  EXPECT_TRUE(m) << m.error().message;
  return m ? (*m)->render() : Image{};
}

TEST(GlRaymarch, ConvergesToTheReferenceAsStepsGrow) {
  REQUIRE_GL_CONTEXT();
  for (const char* json : {"spot", "directional"}) {
    const Light light = test::light_from_json(
        std::string(json) == "spot" ? test::spot_json("linear") : test::directional_json("linear"));
    const DepthImage map = test::scene_shadow_map(light, kMap, kMap);
    Result<Mesh> volume = build_static_volume(light, map, {}, "shadow");
    ASSERT_TRUE(volume);
    const RenderScene scene =
        test::make_render_scene(test::make_camera({6, 3, 6}, {0, 1, 0}, kW, kH), light, medium());
    const Image ref = render_reference(*volume, scene);
    double previous = 1e300;
    for (int n : {4, 16, 64, 256, 1024}) {
      MarchOptions o;
      o.samples = n;
      const double e = compare_images(march(scene, map, o), ref).relative_l2;
      std::printf("  %s N=%4d M=1: relative L2 %.4f\n", json, n, e);
      EXPECT_LT(e, previous * 1.05) << json << " N " << n;
      previous = std::min(previous, e);
    }
    EXPECT_LT(previous, 0.03) << json;
    // Interleaved 4x4 sampling converges to the reference seen through the same 4-wide separable
    // box gather (the gather's blur across edges is the method's bias, not noise).
    const Image blurred = box_gather(ref, 4);
    double previous_m4 = 1e300;
    for (int n : {16, 64, 256}) {
      MarchOptions o;
      o.samples = n;
      o.interleave = 4;
      const double e = compare_images(march(scene, map, o), blurred).relative_l2;
      std::printf("  %s N=%4d M=4: relative L2 %.4f\n", json, n, e);
      EXPECT_LT(e, previous_m4) << json << " N " << n;
      previous_m4 = e;
    }
    EXPECT_LT(previous_m4, 0.03) << json;
  }
}

TEST(GlRaymarch, OmniFacesConvergeToTheOmniVolume) {
  REQUIRE_GL_CONTEXT();
  const Light light = test::light_from_json(
      R"({"type": "omni", "position": [0.3, 2.5, 0.2], "near": 0.1, "far": 30, "depth": "linear"})");
  CubeFaces cube;
  std::vector<DepthImage> maps;
  std::vector<std::string> sources;
  for (int f = 0; f < kOmniFaces; ++f) {
    cube.faces[f] = test::scene_shadow_map(light, 64, 64, {}, f);
    cube.sources[f] = omni_face_name(f);
    maps.push_back(cube.faces[f]);
    sources.push_back(cube.sources[f]);
  }
  Result<Mesh> volume = build_omni_volume(light, cube, {});
  ASSERT_TRUE(volume) << volume.error().message;
  const RenderScene scene =
      test::make_render_scene(test::make_camera({5, 1.5, 4}, {0, 1, 0}, kW, kH), light, medium());
  const Image ref = render_reference(*volume, scene);
  // Pixels whose ray passes within 0.2 rad of the light hold the 1/d² peak that a uniform marcher
  // resolves only as 1/N; the faces' lookups are checked on all others.
  auto away_from_light = [&](const Image& image) {
    Image out = image;
    for (int row = 0; row < kH; ++row)
      for (int col = 0; col < kW; ++col) {
        const Ray ray = pixel_ray(scene.camera, col, row);
        if (dot(normalize(light.position - ray.origin), ray.direction) > std::cos(0.2))
          out.values[static_cast<std::size_t>(row) * kW + col] = 0;
      }
    return out;
  };
  const Image ref_away = away_from_light(ref);
  double previous = 1e300;
  for (int n : {16, 64, 256}) {
    MarchOptions o;
    o.samples = n;
    Result<std::unique_ptr<GlMarcher>> m = GlMarcher::create(scene, maps, sources, o);
    ASSERT_TRUE(m) << m.error().message;
    const double e = compare_images(away_from_light((*m)->render()), ref_away).relative_l2;
    std::printf("  omni N=%4d: relative L2 away from the light %.4f\n", n, e);
    EXPECT_LT(e, previous);
    previous = e;
  }
  EXPECT_LT(previous, 0.01);
}

TEST(GlRadial, GivesAFiniteGlowAroundTheLight) {
  REQUIRE_GL_CONTEXT();
  const Light light = test::light_from_json(test::spot_json("linear"));
  // Looking at the light from below, past the box: the light is on screen.
  const RenderScene scene =
      test::make_render_scene(test::make_camera({4, 1, 4}, {0, 4, 0}, kW, kH), light, medium());
  MarchOptions o;
  o.method = MarchMethod::radial;
  Result<std::unique_ptr<GlMarcher>> m = GlMarcher::create(scene, {}, {}, o);
  ASSERT_TRUE(m) << m.error().message;
  const Image image = (*m)->render();
  double centre = 0, corner = 0;
  for (double v : image.values) ASSERT_TRUE(std::isfinite(v) && v >= 0);
  centre = image.at(kW / 2, kH / 2);
  corner = image.at(0, kH - 1);
  EXPECT_GT(centre, 0);
  EXPECT_GT(centre, corner);
}

TEST(GlRaymarch, RejectsTheWrongNumberOfMaps) {
  REQUIRE_GL_CONTEXT();
  const Light light = test::light_from_json(test::spot_json("linear"));
  const RenderScene scene =
      test::make_render_scene(test::make_camera({6, 3, 6}, {0, 1, 0}, 8, 6), light, medium());
  const DepthImage map = test::scene_shadow_map(light, 8, 8);
  Result<std::unique_ptr<GlMarcher>> m = GlMarcher::create(scene, {map, map}, {"a", "b"}, {});
  ASSERT_FALSE(m);
  EXPECT_EQ(m.error().message, "raymarch: a spot light takes 1 shadow map(s), got 2");
}

}  // namespace
}  // namespace lightvol
