// The CPU reference against brute-force integration with analytic visibility, on a floor and a box
// lit by a spot and a directional light.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include <lightvol/airlight/heterogeneous.h>
#include <lightvol/render/reference.h>
#include <lightvol/render/surfaces.h>
#include <lightvol/volume/static_volume.h>

#include "support/analytic_scene.h"
#include "support/test_support.h"

namespace lightvol {
namespace {

Medium test_medium(Phase phase) {
  Medium m;
  m.scattering = 0.06;
  m.absorption = 0.02;
  m.intensity = 20;
  m.phase = phase;
  return m;
}

struct Case {
  const char* name;
  std::string light_json;
  Vec3d eye, target;
  Phase phase;
  SpotProfile profile = {};
};

void expect_reference_matches_brute_force(const Case& c) {
  SCOPED_TRACE(c.name);
  constexpr int kMap = 512, kW = 24, kH = 18;
  const Light light = test::light_from_json(c.light_json);
  const DepthImage shadow = test::scene_shadow_map(light, kMap, kMap);
  Result<Mesh> volume = build_static_volume(light, shadow, {}, "shadow");
  ASSERT_TRUE(volume) << volume.error().message;
  Medium medium = test_medium(c.phase);
  medium.profile = c.profile;
  const RenderScene scene =
      test::make_render_scene(test::make_camera(c.eye, c.target, kW, kH), light, medium);
  const Image ref = render_reference(*volume, scene);
  Image brute = ref;
  for (int row = 0; row < kH; ++row)
    for (int col = 0; col < kW; ++col)
      brute.values[static_cast<std::size_t>(row) * kW + col] =
          test::brute_force_airlight(scene, kMap, kMap, col, row, 20000, 60.0);
  const ImageDifference diff = compare_images(ref, brute);
  double total = 0;
  for (double v : brute.values) total += v;
  EXPECT_GT(total, 0);
  EXPECT_LT(diff.relative_l2, 0.01) << "max abs " << diff.max_abs << " psnr " << diff.psnr_db;
}

// ---- media of varying density -------------------------------------------------------------------

Density test_noise(double offset, double scale) {
  Density d;
  d.type = DensityType::noise;
  d.noise.seed = 3;
  d.noise.frequency = 0.5;
  d.noise.octaves = 3;
  d.noise.offset = offset;
  d.noise.scale = scale;
  return d;
}

struct DensityCase {
  const char* name;
  std::string light_json;
  Vec3d eye, target;
};

const DensityCase kDensityCases[] = {
    {"spot outside", test::spot_json("linear"), {6, 3, 6}, {0, 1, 0}},
    {"spot inside", test::spot_json("linear"), {1.5, 0.6, 1.5}, {-1, 0.3, -1}},
    {"directional outside", test::directional_json("linear"), {7, 4, 5}, {0, 0.5, 0}},
};

RenderScene density_scene(const DensityCase& c, const Density& density, int w, int h, Mesh* volume,
                          int map = 128) {
  const Light light = test::light_from_json(c.light_json);
  const DepthImage shadow = test::scene_shadow_map(light, map, map);
  Result<Mesh> built = build_static_volume(light, shadow, {}, "shadow");
  EXPECT_TRUE(built) << built.error().message;
  if (built) *volume = std::move(*built);
  Medium medium = test_medium({PhaseType::hg, 0.3, 0});
  medium.density = density;
  return test::make_render_scene(test::make_camera(c.eye, c.target, w, h), light, medium);
}

// Noise of zero amplitude is the homogeneous medium: the quadrature along the lit intervals gives
// the closed form's image.
TEST(Reference, ConstantDensityIsTheHomogeneousImage) {
  for (const DensityCase& c : kDensityCases) {
    SCOPED_TRACE(c.name);
    Mesh volume;
    RenderScene scene = density_scene(c, test_noise(1.0, 0.0), 24, 18, &volume);
    const Image marched = render_reference(volume, scene);
    scene.medium.density = {};
    const Image closed = render_reference(volume, scene);
    const ImageDifference d = compare_images(marched, closed);
    EXPECT_LT(d.relative_l2, 1e-6) << "max abs " << d.max_abs;
    double total = 0;
    for (double v : closed.values) total += v;
    EXPECT_GT(total, 0);
  }
}

// The quadrature against midpoint sums with analytic visibility (the floor and box cast exactly).
TEST(Reference, VaryingDensityMatchesBruteForce) {
  constexpr int kW = 12, kH = 9, kMap = 512;
  for (const DensityCase& c : kDensityCases) {
    SCOPED_TRACE(c.name);
    Mesh volume;
    const RenderScene scene = density_scene(c, test_noise(0.6, 0.9), kW, kH, &volume, kMap);
    const Image ref = render_reference(volume, scene);
    Image brute = ref;
    for (int row = 0; row < kH; ++row)
      for (int col = 0; col < kW; ++col)
        brute.values[static_cast<std::size_t>(row) * kW + col] =
            test::brute_force_airlight(scene, kMap, kMap, col, row, 2000, 60.0);
    const ImageDifference d = compare_images(ref, brute);
    // The same scene homogeneous differs by far more than the tolerance: the density matters.
    RenderScene flat = scene;
    flat.medium.density = {};
    const ImageDifference from_flat = compare_images(render_reference(volume, flat), brute);
    std::printf("  %-20s relative L2 vs brute force %.2e (homogeneous: %.2e)\n", c.name,
                d.relative_l2, from_flat.relative_l2);
    // Measured 7.3e-3, 3.0e-3, 7.9e-4: the brute force's midpoint sums and its exact edges against
    // the 512² map's on 108 pixels.
    EXPECT_LT(d.relative_l2, 0.015);
    EXPECT_GT(from_flat.relative_l2, 0.1);
  }
}

TEST(Reference, LitIntervalsFollowTheCrossingSigns) {
  // Eye outside: enter at 1, leave at 3, enter at 5, leave at 8 (clamped).
  std::vector<LitInterval> lit = lit_intervals({{5, -1}, {1, -1}, {8, 1}, {3, 1}});
  ASSERT_EQ(lit.size(), 2u);
  EXPECT_EQ(lit[0].a, 1);
  EXPECT_EQ(lit[0].b, 3);
  EXPECT_EQ(lit[1].a, 5);
  EXPECT_EQ(lit[1].b, 8);
  EXPECT_EQ(lit[1].weight, 1);
  // Eye inside: lit from 0 to the first exit.
  lit = lit_intervals({{2, 1}});
  ASSERT_EQ(lit.size(), 1u);
  EXPECT_EQ(lit[0].a, 0);
  EXPECT_EQ(lit[0].b, 2);
  // Both crossings clamped to the same surface distance: nothing lit.
  EXPECT_TRUE(lit_intervals({{4, -1}, {4, 1}}).empty());
}

TEST(Reference, SpotLightMatchesBruteForceFromOutside) {
  expect_reference_matches_brute_force(
      {"spot outside", test::spot_json("linear"), {6, 3, 6}, {0, 1, 0}, {PhaseType::hg, 0.4, 0}});
}

TEST(Reference, SpotLightMatchesBruteForceFromInside) {
  expect_reference_matches_brute_force({"spot inside",
                                        test::spot_json("linear"),
                                        {1.5, 0.6, 1.5},
                                        {-1, 0.3, -1},
                                        {PhaseType::isotropic}});
}

TEST(Reference, SoftEdgedSpotMatchesBruteForce) {
  expect_reference_matches_brute_force({"spot profile",
                                        test::spot_json("linear"),
                                        {6, 3, 6},
                                        {0, 1, 0},
                                        {PhaseType::hg, 0.4, 0},
                                        {12, 24}});
}

// Before: a ray through an edge shared by two triangles could miss both (Möller–Trumbore rounds
// each triangle's barycentrics its own way), losing a crossing: with the camera above a spot
// looking down through its apex, four pixels were 13x their neighbours. Cameras that see the apex,
// look into the light, or sit inside the volume.
TEST(Reference, CamerasThroughTheApexIntoTheLightAndInsideMatchBruteForce) {
  expect_reference_matches_brute_force({"sees the apex",
                                        test::spot_json("linear"),
                                        {0.02, 8, 0.01},
                                        {0, 0, 0},
                                        {PhaseType::isotropic}});
  expect_reference_matches_brute_force({"looks into the light",
                                        test::spot_json("linear"),
                                        {2.5, 0.4, 1.5},
                                        {0, 4, 0},
                                        {PhaseType::hg, 0.4, 0}});
  // Inside, looking up beside the light (a ray through the light itself is infinite: 1/r²).
  expect_reference_matches_brute_force({"inside, beside the light",
                                        test::spot_json("linear"),
                                        {0.4, 2.5, 0.3},
                                        {-0.5, 3.5, -0.5},
                                        {PhaseType::isotropic}});
}

// The scene of the report: spot at (0, 10, 0) looking down at a floor at its far plane, camera at
// (0, 20, 0) looking down through the apex, 64x64. The image is symmetric under the quarter turns
// of the square frustum; a lost crossing broke that at four pixels.
TEST(Reference, ApexViewIsSymmetric) {
  const Light light = test::light_from_json(
      R"({"type": "spot", "position": [0, 10, 0], "direction": [0, -1, 0], "up": [0, 0, -1],
          "fov_y_deg": 60, "near": 1, "far": 20})");
  const DepthImage shadow = test::constant_depth(64, 64, 1.0f);
  Result<Mesh> volume = build_static_volume(light, shadow, {}, "shadow");
  ASSERT_TRUE(volume) << volume.error().message;
  constexpr int kN = 64;
  const Result<Camera> camera = parse_camera(
      R"({"type": "spot", "position": [0, 20, 0], "direction": [0, -1, 0], "up": [0, 0, -1],
          "fov_y_deg": 60, "near": 0.5, "far": 40, "width": 64, "height": 64})",
      "camera.json");
  ASSERT_TRUE(camera) << camera.error().message;
  const RenderScene scene =
      test::make_render_scene(*camera, light, test_medium({PhaseType::isotropic}));
  const Image ref = render_reference(*volume, scene);
  double worst = 0;
  for (int row = 0; row < kN; ++row)
    for (int col = 0; col < kN; ++col) {
      const double a = ref.values[static_cast<std::size_t>(row) * kN + col];
      const double b = ref.values[static_cast<std::size_t>(col) * kN + (kN - 1 - row)];
      const double c = ref.values[static_cast<std::size_t>(row) * kN + (kN - 1 - col)];
      worst = std::max({worst, std::abs(a - b) / std::max(1e-12, std::abs(a) + std::abs(b)),
                        std::abs(a - c) / std::max(1e-12, std::abs(a) + std::abs(c))});
    }
  EXPECT_LT(worst, 1e-3);
}

TEST(Reference, DirectionalLightMatchesBruteForce) {
  expect_reference_matches_brute_force({"directional",
                                        test::directional_json("linear"),
                                        {7, 4, 5},
                                        {0, 0.5, 0},
                                        {PhaseType::schlick, 0, 0.3}});
}

TEST(Reference, EmptyVolumeGivesZero) {
  const Light light = test::light_from_json(test::spot_json("linear"));
  const RenderScene scene = test::make_render_scene(test::make_camera({6, 3, 6}, {0, 1, 0}, 8, 6),
                                                    light, test_medium({}));
  const Image image = render_reference(Mesh{}, scene);
  for (double v : image.values) EXPECT_EQ(v, 0);
}

// `render --composite`: surfaces of constant radiance seen through the medium. A constant density
// gives the homogeneous composite; a noise density dims each pixel by its own eye-side
// transmittance e^(−σt ∫ρ), here against a fine midpoint sum of ρ along the pixel's ray.
TEST(Composite, ConstantSurfacesSeenThroughTheDensity) {
  const Light light = test::light_from_json(test::spot_json("linear"));
  Medium m = test_medium({PhaseType::isotropic});
  m.scattering = 0.3;
  m.absorption = 0.1;
  const Camera camera = test::make_camera({6, 3, 6}, {0, 0.5, 0}, 24, 18);
  const RenderScene flat = test::make_render_scene(camera, light, m);
  const auto composite = [](const RenderScene& scene) {
    Image image;
    image.width = scene.camera.width;
    image.height = scene.camera.height;
    image.values.assign(scene.surface.size(), 0.25);  // an airlight to add to
    add_constant_surfaces(scene, 2.0, &image);
    return image;
  };
  const Image homogeneous = composite(flat);
  RenderScene constant = flat;
  constant.medium.density.type = DensityType::noise;
  constant.medium.density.noise.offset = 1;
  constant.medium.density.noise.scale = 0;
  ASSERT_TRUE(constant.medium.density.varying());
  const ImageDifference same = compare_images(composite(constant), homogeneous);
  std::printf("  constant density vs homogeneous composite: relative L2 %.2e\n", same.relative_l2);
  EXPECT_LT(same.relative_l2, 1e-12);

  RenderScene thick = flat;
  thick.medium.density.type = DensityType::noise;
  thick.medium.density.noise.seed = 11;
  thick.medium.density.noise.frequency = 0.6;
  thick.medium.density.noise.octaves = 3;
  thick.medium.density.noise.offset = 0.5;
  thick.medium.density.noise.scale = 0.8;
  const Image noisy = composite(thick);
  int surfaces = 0, classified = 0, right = 0;
  double worst = 0;
  for (int row = 0; row < camera.height; ++row)
    for (int col = 0; col < camera.width; ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * camera.width + col;
      const double s = flat.surface[i];
      if (!std::isfinite(s)) {
        EXPECT_EQ(noisy.values[i], 0.25);  // nothing seen: the airlight alone
        continue;
      }
      ++surfaces;
      const Ray ray = pixel_ray(camera, col, row);
      double integral = 0;  // ∫ρ by the midpoint rule, 4,000 steps
      for (int k = 0; k < 4000; ++k)
        integral += thick.medium.density(ray.origin + ((k + 0.5) / 4000 * s) * ray.direction);
      integral *= s / 4000;
      const double expected = 0.25 + 2.0 * std::exp(-m.extinction() * integral);
      worst = std::max(worst, std::abs(noisy.values[i] - expected) / expected);
      // Where the noise is thicker than 1 on average along the ray, the surface is dimmer than in
      // the homogeneous medium; where thinner, brighter.
      if (integral > 1.1 * s || integral < 0.9 * s) {
        ++classified;
        right += (integral > s) == (noisy.values[i] < homogeneous.values[i]);
      }
    }
  std::printf(
      "  noise: %d surface pixels, %d of them 10 %% off the mean density; worst relative error "
      "%.2e\n",
      surfaces, classified, worst);
  EXPECT_GT(surfaces, 200);
  EXPECT_LT(worst, 3e-3);  // panels of twice the finest wavelength: measured 8.7e-4
  EXPECT_GT(classified, surfaces / 2);
  EXPECT_EQ(right, classified);
  EXPECT_GT(compare_images(noisy, homogeneous).relative_l2, 0.05);
}

}  // namespace
}  // namespace lightvol
