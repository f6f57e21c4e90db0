// The GPU `volume` method against the CPU reference on the same meshes: spot and directional
// lights, camera outside and inside the volume, lit floor and box surfaces in view, all phases.
#include <cmath>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include <lightvol/depth/cube_faces.h>
#include <lightvol/render/gl_volume.h>
#include <lightvol/render/reference.h>
#include <lightvol/volume/omni_volume.h>
#include <lightvol/volume/static_volume.h>

#include "support/analytic_scene.h"
#include "support/gl_test_context.h"
#include "support/test_support.h"

namespace lightvol {
namespace {

struct Case {
  const char* name;
  std::string light_json;
  Vec3d eye, target;
  Phase phase;
  SpotProfile profile = {};
};

constexpr int kMap = 96, kW = 64, kH = 48;

ImageDifference volume_vs_reference(const Case& c, const GlVolumeOptions& options,
                                    Image* gl_image = nullptr) {
  const Light light = test::light_from_json(c.light_json);
  const DepthImage shadow = test::scene_shadow_map(light, kMap, kMap);
  Result<Mesh> volume = build_static_volume(light, shadow, {}, "shadow");
  EXPECT_TRUE(volume) << volume.error().message;
  Medium m;
  m.scattering = 0.06;
  m.absorption = 0.02;
  m.intensity = 20;
  m.phase = c.phase;
  m.profile = c.profile;
  const RenderScene scene =
      test::make_render_scene(test::make_camera(c.eye, c.target, kW, kH), light, m);
  const Image ref = render_reference(*volume, scene);
  Result<std::unique_ptr<GlVolumeRenderer>> renderer = GlVolumeRenderer::create(scene, options);
  EXPECT_TRUE(renderer) << renderer.error().message;
  if (!renderer) return {1, 1, 0};
  (*renderer)->set_volume(*volume);
  const Image image = (*renderer)->render();
  if (gl_image) *gl_image = image;
  double total = 0;
  for (double v : ref.values) total += v;
  EXPECT_GT(total, 0) << c.name;
  return compare_images(image, ref);
}

const Case kCases[] = {
    {"spot outside hg", test::spot_json("linear"), {6, 3, 6}, {0, 1, 0}, {PhaseType::hg, 0.4, 0}},
    {"spot outside isotropic",
     test::spot_json("linear"),
     {-5, 2, 4},
     {0, 0.5, 0},
     {PhaseType::isotropic}},
    {"spot inside isotropic",
     test::spot_json("linear"),
     {1.5, 0.6, 1.5},
     {-1, 0.3, -1},
     {PhaseType::isotropic}},
    {"spot inside schlick",
     test::spot_json("linear"),
     {0.8, 2.5, 0.3},
     {-1, 0, -1},
     {PhaseType::schlick, 0, -0.3}},
    {"soft spot outside hg",
     test::spot_json("linear"),
     {6, 3, 6},
     {0, 1, 0},
     {PhaseType::hg, 0.4, 0},
     {12, 24}},
    {"soft spot inside isotropic",
     test::spot_json("linear"),
     {1.5, 0.6, 1.5},
     {-1, 0.3, -1},
     {PhaseType::isotropic},
     {5, 28}},
    {"directional outside hg",
     test::directional_json("linear"),
     {7, 4, 5},
     {0, 0.5, 0},
     {PhaseType::hg, 0.2, 0}},
    {"directional inside isotropic",
     test::directional_json("linear"),
     {2, 1, 2},
     {-1, 0.5, -2},
     {PhaseType::isotropic}},
    // Cameras that see the spot's apex, look into the light, or sit inside looking at it (a
    // reference that lost crossings at shared edges made these disagree 13x at some pixels).
    {"spot apex seen from above",
     test::spot_json("linear"),
     {0.02, 8, 0.01},
     {0, 0, 0},
     {PhaseType::isotropic}},
    {"spot looked into",
     test::spot_json("linear"),
     {2.5, 0.4, 1.5},
     {0, 4, 0},
     {PhaseType::hg, 0.4, 0}},
    {"spot inside beside the light",
     test::spot_json("linear"),
     {0.4, 2.5, 0.3},
     {-0.5, 3.5, -0.5},
     {PhaseType::isotropic}},
};

TEST(GlVolume, MatchesTheReferenceWithinTwoTenthsOfAPercent) {
  REQUIRE_GL_CONTEXT();
  for (const Case& c : kCases) {
    const ImageDifference d = volume_vs_reference(c, {});
    std::printf("  %-30s relative L2 %.2e  max abs %.2e  PSNR %.1f dB\n", c.name, d.relative_l2,
                d.max_abs, d.psnr_db);
    EXPECT_LT(d.relative_l2, 0.002) << c.name;
  }
}

TEST(GlVolume, BaselineAtTheClosestPointDoesNotLoseAccuracy) {
  REQUIRE_GL_CONTEXT();
  for (const Case& c : kCases) {
    GlVolumeOptions from_eye;
    from_eye.baseline = false;
    const ImageDifference with = volume_vs_reference(c, {});
    const ImageDifference without = volume_vs_reference(c, from_eye);
    std::printf("  %-30s relative L2 with baseline %.2e, from the eye %.2e\n", c.name,
                with.relative_l2, without.relative_l2);
    // Measured (llvmpipe): never more than 4% worse (5.16e-06 against 4.98e-06, spot outside hg),
    // 17× and 6× better on the soft spot; the bounds leave a margin of 10% and half of that.
    EXPECT_LE(with.relative_l2, 1.1 * without.relative_l2 + 1e-8) << c.name;
    if (std::string(c.name).rfind("soft spot", 0) == 0) {
      EXPECT_LT(3 * with.relative_l2, without.relative_l2) << c.name;
    }
  }
}

TEST(GlVolume, OmniMatchesTheReferenceInsideAndOutside) {
  REQUIRE_GL_CONTEXT();
  const Light light = test::light_from_json(
      R"({"type": "omni", "position": [0.3, 2.5, 0.2], "near": 0.1, "far": 30, "depth": "linear"})");
  Result<Mesh> volume = build_omni_volume(light, test::scene_cube_faces(light, 48), {});
  ASSERT_TRUE(volume) << volume.error().message;
  Medium m;
  m.scattering = 0.05;
  m.absorption = 0.02;
  m.intensity = 10;
  m.phase = {PhaseType::hg, 0.3, 0};
  // Lit space around the camera; then the camera in the box's shadow, looking out of it.
  for (auto [eye, target] :
       {std::pair<Vec3d, Vec3d>{{5, 3, 5}, {0, 1, 0}}, {{0.3, 0.5, 0.2}, {3, 0.9, 1}}}) {
    const RenderScene scene =
        test::make_render_scene(test::make_camera(eye, target, kW, kH), light, m);
    const Image ref = render_reference(*volume, scene);
    Result<std::unique_ptr<GlVolumeRenderer>> renderer = GlVolumeRenderer::create(scene);
    ASSERT_TRUE(renderer) << renderer.error().message;
    (*renderer)->set_volume(*volume);
    const ImageDifference d = compare_images((*renderer)->render(), ref);
    double total = 0;
    for (double v : ref.values) total += v;
    std::printf("  omni eye (%g, %g, %g): relative L2 %.2e  max abs %.2e  mean %.3g\n", eye.x,
                eye.y, eye.z, d.relative_l2, d.max_abs,
                total / static_cast<double>(ref.values.size()));
    EXPECT_GT(total, 0);
    EXPECT_LT(d.relative_l2, 0.002);
  }
}

}  // namespace
}  // namespace lightvol
