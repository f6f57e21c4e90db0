// The airlight maths of docs/design.md §6 against direct numerical integration, and the medium and
// camera descriptions' parsing.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <gtest/gtest.h>

#include <lightvol/airlight/airlight.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

// Midpoint rule with n samples of f on [a, b].
template <class F>
double midpoint(const F& f, double a, double b, int n) {
  const double h = (b - a) / n;
  double s = 0;
  for (int i = 0; i < n; ++i) s += f(a + (i + 0.5) * h);
  return s * h;
}

TEST(SunF, MatchesItsDefinition) {
  EXPECT_DOUBLE_EQ(sun_f(0, 1.2), 1.2);
  for (double u : {0.01, 0.3, 2.0, 15.0})
    for (double v : {0.1, 0.7, 1.5, std::numbers::pi / 2}) {
      const double direct =
          midpoint([u](double x) { return std::exp(-u * std::tan(x)); }, 0, v, 400000);
      EXPECT_NEAR(sun_f(u, v), direct, 1e-8) << "u " << u << " v " << v;
    }
}

TEST(Phase, IsNormalizedOverTheSphere) {
  for (Phase p : {Phase{PhaseType::isotropic}, Phase{PhaseType::hg, 0.7, 0},
                  Phase{PhaseType::hg, -0.4, 0}, Phase{PhaseType::schlick, 0, 0.6}}) {
    const double total =
        2 * std::numbers::pi * midpoint([&](double c) { return p(c); }, -1, 1, 200000);
    EXPECT_NEAR(total, 1.0, 1e-6) << to_string(p.type);
  }
}

// La(0, t) by brute force in s, straight from the integrand of docs/design.md §6.
double point_brute(const Light& light, const Medium& m, const Ray& ray, double t) {
  return midpoint(
      [&](double s) {
        const Vec3d x = ray.origin + s * ray.direction;
        const double d = length(x - light.position);
        const double cos_theta = dot((1.0 / d) * (x - light.position), -1.0 * ray.direction);
        return m.scattering * m.intensity * std::exp(-m.extinction() * d) / (d * d) *
               m.phase(cos_theta) * std::exp(-m.extinction() * s);
      },
      0, t, 400000);
}

TEST(RayAirlight, PointLightMatchesDirectIntegration) {
  const Light light = test::light_from_json(test::spot_json());
  Medium m;
  m.scattering = 0.08;
  m.absorption = 0.03;
  m.intensity = 30;
  for (Phase phase : {Phase{PhaseType::isotropic}, Phase{PhaseType::hg, 0.6, 0},
                      Phase{PhaseType::schlick, 0, -0.5}}) {
    m.phase = phase;
    // Rays passing the light in front, beside and behind the eye.
    for (auto [origin, target] : {std::pair<Vec3d, Vec3d>{{5, 1, 3}, {-3, 3, -1}},
                                  {{0.5, 0.5, 0.5}, {2, 1, 3}},
                                  {{-2, 6, 1}, {3, 0, 0}}}) {
      Ray ray{origin, normalize(target - origin)};
      const RayAirlight la(light, m, ray);
      for (double t : {0.3, 2.0, 7.5, 20.0}) {
        const double direct = point_brute(light, m, ray, t);
        EXPECT_NEAR(la(t), direct, 1e-7 * std::abs(direct) + 1e-12)
            << to_string(phase.type) << " t " << t;
      }
      EXPECT_EQ(la(0), 0);
      EXPECT_GT(la(std::numeric_limits<double>::infinity()), la(20.0));
    }
  }
}

TEST(RayAirlight, SpotProfileMatchesDirectIntegration) {
  const Light light = test::light_from_json(test::spot_json());
  Medium m;
  m.scattering = 0.08;
  m.absorption = 0.03;
  m.intensity = 30;
  m.phase = {PhaseType::hg, 0.5, 0};
  m.profile = {10, 25};
  for (auto [origin, target] :
       {std::pair<Vec3d, Vec3d>{{5, 1, 3}, {-3, 1.5, -1}}, {{0.5, 0.5, 0.5}, {2, 1, 3}}}) {
    Ray ray{origin, normalize(target - origin)};
    const RayAirlight la(light, m, ray);
    for (double t : {2.0, 7.5, 20.0}) {
      const double direct = midpoint(
          [&](double s) {
            const Vec3d x = ray.origin + s * ray.direction;
            const double d = length(x - light.position);
            const Vec3d l = (1.0 / d) * (x - light.position);
            return m.scattering * m.intensity * std::exp(-m.extinction() * d) / (d * d) *
                   m.phase(dot(l, -1.0 * ray.direction)) * m.profile(dot(l, light.direction)) *
                   std::exp(-m.extinction() * s);
          },
          0, t, 400000);
      EXPECT_NEAR(la(t), direct, 1e-7 * std::abs(direct) + 1e-12) << "t " << t;
    }
  }
  // The profile: 1 inside the inner cone, 0 outside the outer one, smooth between.
  EXPECT_EQ(m.profile(std::cos(5 * std::numbers::pi / 180)), 1.0);
  EXPECT_EQ(m.profile(std::cos(30 * std::numbers::pi / 180)), 0.0);
  const double mid = m.profile(std::cos(17.5 * std::numbers::pi / 180));
  EXPECT_GT(mid, 0.3);
  EXPECT_LT(mid, 0.7);
}

TEST(RayAirlight, DirectionalClosedFormMatchesDirectIntegration) {
  const Light light = test::light_from_json(test::directional_json());
  Medium m;
  m.scattering = 0.1;
  m.absorption = 0.05;
  m.intensity = 3;
  m.phase = {PhaseType::hg, 0.4, 0};
  for (Vec3d dir : {Vec3d{1, -1, 0.2}, Vec3d{0, 1, 0}, Vec3d{0.3, -0.2, 1}}) {
    Ray ray{{1, 2, -1}, normalize(dir)};
    const RayAirlight la(light, m, ray);
    const double k = dot(ray.direction, light.direction);
    for (double t : {0.5, 3.0, 9.0}) {
      const double direct = midpoint(
          [&](double s) {
            const Vec3d x = ray.origin + s * ray.direction;
            const double z = dot(x - light.position, light.direction);
            return m.scattering * m.intensity * std::exp(-m.extinction() * z) * m.phase(-k) *
                   std::exp(-m.extinction() * s);
          },
          0, t, 100000);
      EXPECT_NEAR(la(t), direct, 1e-8 * direct) << "k " << k << " t " << t;
    }
  }
}

TEST(Medium, ParsesAllKeys) {
  Result<Medium> m = parse_medium(
      R"({"scattering": 0.05, "absorption": 0.01, "intensity": 40, "phase": {"type": "hg", "g": 0.3}})",
      "m.json");
  ASSERT_TRUE(m) << m.error().message;
  EXPECT_EQ(m->scattering, 0.05);
  EXPECT_EQ(m->absorption, 0.01);
  EXPECT_EQ(m->intensity, 40);
  EXPECT_EQ(m->phase.type, PhaseType::hg);
  EXPECT_EQ(m->phase.g, 0.3);
  EXPECT_DOUBLE_EQ(m->extinction(), 0.06);
  EXPECT_FALSE(m->profile.enabled());
  Result<Medium> p = parse_medium(
      R"({"scattering": 0.05, "profile": {"inner_deg": 15, "outer_deg": 25}})", "p.json");
  ASSERT_TRUE(p) << p.error().message;
  EXPECT_TRUE(p->profile.enabled());
  EXPECT_EQ(p->profile.inner_deg, 15);
  EXPECT_EQ(p->profile.outer_deg, 25);
}

TEST(Medium, ParsesANoiseDensity) {
  Result<Medium> m = parse_medium(
      R"({"scattering": 0.05, "density": {"type": "noise", "seed": 4294967295, "frequency": 0.7,
          "octaves": 5, "lacunarity": 2.5, "gain": 0.4, "offset": 0.8, "scale": 0.6}})",
      "m.json");
  ASSERT_TRUE(m) << m.error().message;
  EXPECT_EQ(m->density.type, DensityType::noise);
  EXPECT_EQ(m->density.noise.seed, 4294967295u);
  EXPECT_EQ(m->density.noise.frequency, 0.7);
  EXPECT_EQ(m->density.noise.octaves, 5);
  EXPECT_EQ(m->density.noise.lacunarity, 2.5);
  EXPECT_EQ(m->density.noise.gain, 0.4);
  EXPECT_EQ(m->density.noise.offset, 0.8);
  EXPECT_EQ(m->density.noise.scale, 0.6);
  EXPECT_DOUBLE_EQ(m->density.finest_wavelength(), 1 / (0.7 * std::pow(2.5, 4)));
  Result<Medium> d = parse_medium(R"({"scattering": 0.05, "density": {"type": "noise"}})", "d");
  ASSERT_TRUE(d) << d.error().message;
  EXPECT_TRUE(d->density.varying());
  EXPECT_EQ(d->density.noise.octaves, NoiseDensity{}.octaves);
  Result<Medium> h = parse_medium(R"({"scattering": 0.05})", "h");
  ASSERT_TRUE(h) << h.error().message;
  EXPECT_FALSE(h->density.varying());
}

// The documented field: in range, continuous across lattice planes, zero amplitude constant,
// different seeds different fields, max(0, ·) clamping.
TEST(Density, NoiseIsTheDocumentedFbm) {
  NoiseDensity n;
  n.seed = 7;
  n.frequency = 1.3;
  double lo = 1, hi = -1, mean = 0;
  const int count = 20000;
  for (int i = 0; i < count; ++i) {
    const Vec3d x{0.37 * i, -0.11 * i + 3, 0.023 * i - 50};
    const double b = noise_fbm(n, x);
    lo = std::min(lo, b);
    hi = std::max(hi, b);
    mean += b / count;
  }
  EXPECT_GE(lo, -1.0);
  EXPECT_LT(hi, 1.0);
  EXPECT_LT(lo, -0.4);  // the field does vary
  EXPECT_GT(hi, 0.4);
  EXPECT_NEAR(mean, 0.0, 0.05);
  // Continuous across a lattice plane (x = 2 in noise coordinates), on either side of zero.
  for (double plane : {2.0, -3.0}) {
    const double a = value_noise({plane - 1e-9, 0.3, 0.7}, 5);
    const double b = value_noise({plane + 1e-9, 0.3, 0.7}, 5);
    EXPECT_NEAR(a, b, 1e-7);
  }
  // At a lattice point the noise is the hashed value itself: a different seed, a different value.
  EXPECT_NE(value_noise({1, 2, 3}, 1), value_noise({1, 2, 3}, 2));
  // One octave with gain 0: the fBm is the first octave alone.
  NoiseDensity single = n;
  single.gain = 0;
  EXPECT_EQ(noise_fbm(single, {0.4, 0.5, 0.6}), value_noise(Vec3d{0.4, 0.5, 0.6} * 1.3, 7));
  Density d;
  d.type = DensityType::noise;
  d.noise = n;
  d.noise.offset = 1.0;
  d.noise.scale = 0.0;
  EXPECT_EQ(d({1.5, -2, 3}), 1.0);
  d.noise.offset = 0.0;
  d.noise.scale = 1.0;
  for (int i = 0; i < 100; ++i) EXPECT_GE(d({0.1 * i, 0.2, 0.3}), 0.0);
  EXPECT_EQ(d.max_density(), 1.0);
  EXPECT_EQ(Density{}({4, 5, 6}), 1.0);
}

TEST(Medium, RejectsBadInputNamingFileAndKey) {
  const std::pair<const char*, const char*> cases[] = {
      {R"({"scattering": 0.1, "densty": 2})", "m.json: key 'densty': unknown key"},
      {R"({"scattering": 0.1, "density": 2})", "m.json: key 'density': expected an object"},
      {R"({"scattering": 0.1, "density": {}})", "m.json: key 'density.type': missing"},
      {R"({"scattering": 0.1, "density": {"type": "perlin"}})",
       "m.json: key 'density.type': expected \"noise\""},
      {R"({"scattering": 0.1, "density": {"type": "vdb", "file": "a.vdb"}})",
       "m.json: key 'density.file': a.vdb: no such file"},
      {R"({"scattering": 0.1, "density": {"type": "vdb"}})", "m.json: key 'density.file': missing"},
      {R"({"scattering": 0.1, "density": {"type": "vdb", "file": "a.vdb", "seed": 1}})",
       "m.json: key 'density.seed': unknown key"},
      {R"({"scattering": 0.1, "density": {"type": "vdb", "file": "a.vdb", "scale": -1}})",
       "m.json: key 'density.scale': must be >= 0, got -1"},
      {R"({"scattering": 0.1, "density": {"type": "noise", "octave": 3}})",
       "m.json: key 'density.octave': unknown key"},
      {R"({"scattering": 0.1, "density": {"type": "noise", "scale": -0.5}})",
       "m.json: key 'density.scale': must be >= 0, got -0.5"},
      {R"({"scattering": 0.1, "density": {"type": "noise", "offset": -1}})",
       "m.json: key 'density.offset': must be >= 0, got -1"},
      {R"({"scattering": 0.1, "density": {"type": "noise", "frequency": 0}})",
       "m.json: key 'density.frequency': must be > 0, got 0"},
      {R"({"scattering": 0.1, "density": {"type": "noise", "octaves": 2.5}})",
       "m.json: key 'density.octaves': must be an integer in [1, 12], got 2.5"},
      {R"({"scattering": 0.1, "density": {"type": "noise", "octaves": 13}})",
       "m.json: key 'density.octaves': must be an integer in [1, 12], got 13"},
      {R"({"scattering": 0.1, "density": {"type": "noise", "seed": -1}})",
       "m.json: key 'density.seed': must be an integer in [0, 4294967295], got -1"},
      {R"({"scattering": 0.1, "density": {"type": "noise", "seed": 4294967296}})",
       "m.json: key 'density.seed': must be an integer in [0, 4294967295]"},
      {R"({"scattering": 0.1, "density": {"type": "noise", "gain": 1.5}})",
       "m.json: key 'density.gain': must be in [0, 1], got 1.5"},
      {R"({"scattering": 0.1, "density": {"type": "noise", "lacunarity": 0.5}})",
       "m.json: key 'density.lacunarity': must be in [1, 16], got 0.5"},
      {R"({"scattering": 0.1, "density": {"type": "noise", "scale": "big"}})",
       "m.json: key 'density.scale': expected a number"},
      {R"({"scattering": 0.1, "density": {"type": "noise", "scale": NaN}})",
       "m.json: not valid JSON"},
      {R"({"absorption": 0.1})", "m.json: key 'scattering': missing"},
      {R"({"scattering": -1})", "m.json: key 'scattering': must be >= 0"},
      {R"({"scattering": 0.1, "phase": {"type": "hg", "g": 1.2}})",
       "m.json: key 'phase.g': must lie in (-1, 1)"},
      {R"({"scattering": 0.1, "phase": {"type": "hg", "k": 0.2}})",
       "m.json: key 'phase.k': does not apply"},
      {R"({"scattering": 0.1, "phase": {"type": "rayleigh"}})",
       "m.json: key 'phase.type': expected"},
      {R"({"scattering": 0.1, "phase": {"type": "hg", "gg": 0.1}})",
       "m.json: key 'phase.gg': unknown key"},
      {R"({"scattering": 0.1, "profile": {"inner_deg": 30, "outer_deg": 20}})",
       "m.json: key 'profile': needs 0 <= inner_deg < outer_deg <= 90"},
      {R"({"scattering": 0.1, "profile": {"outer_deg": 20}})",
       "m.json: key 'profile.inner_deg': missing"},
      {R"({"scattering": 0.1, "profile": {"inner_deg": 1, "outer_deg": 20, "x": 1}})",
       "m.json: key 'profile.x': unknown key"},
      {R"([1, 2])", "m.json: expected a JSON object"},
      {R"({"scattering": )", "m.json: not valid JSON"},
      {R"({"scattering": 1e99999})", "m.json: not valid JSON"},  // beyond double: out_of_range
      {R"({"scattering": 0.1, "phase": [1]})", "m.json: key 'phase': expected an object"},
  };
  for (auto [text, expected] : cases) {
    Result<Medium> m = parse_medium(text, "m.json");
    ASSERT_FALSE(m) << text;
    EXPECT_EQ(m.error().message.rfind(expected, 0), 0u) << m.error().message;
  }
}

TEST(Camera, ParsesALightPlusImageSize) {
  Result<Camera> c = parse_camera(
      R"({"position": [0, 1, 5], "direction": [0, 0, -1], "up": [0, 1, 0], "fov_y_deg": 45,
          "aspect": 1.5, "near": 0.1, "far": 50, "width": 96, "height": 64, "depth": "linear"})",
      "cam.json");
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_EQ(c->width, 96);
  EXPECT_EQ(c->height, 64);
  EXPECT_EQ(c->view.type, LightType::spot);
  EXPECT_EQ(c->view.depth, DepthEncoding::linear);
  // The centre of the image looks along the view direction (even sizes: average two pixels).
  const Ray a = pixel_ray(*c, 47, 31), b = pixel_ray(*c, 48, 32);
  const Vec3d mid = normalize(a.direction + b.direction);
  EXPECT_NEAR(mid.z, -1, 1e-12);
  EXPECT_NEAR(a.origin.z, 5, 1e-12);
  // Top-left pixel looks up and left.
  const Ray tl = pixel_ray(*c, 0, 0);
  EXPECT_LT(tl.direction.x, 0);
  EXPECT_GT(tl.direction.y, 0);
}

TEST(Camera, RejectsBadInputNamingFileAndKey) {
  const std::string base =
      R"("position": [0, 1, 5], "direction": [0, 0, -1], "up": [0, 1, 0], "fov_y_deg": 45, "near": 0.1, "far": 50)";
  const std::pair<std::string, const char*> cases[] = {
      {"{" + base + R"(, "height": 64})", "cam.json: key 'width': missing"},
      {"{" + base + R"(, "width": 0, "height": 64})", "cam.json: key 'width': expected an integer"},
      {"{" + base + R"(, "width": 2.5, "height": 64})",
       "cam.json: key 'width': expected an integer"},
      {"{" + base + R"(, "width": 8, "height": 8, "fov": 3})", "cam.json: key 'fov': unknown key"},
      {"{" + base + R"(, "width": 8, "height": 1e99999})", "cam.json: not valid JSON"},
      {"{" + base + R"(, "width": 8, "height": 8, "width": 9})",
       "cam.json: key \"width\" appears twice in one object"},
      {R"({"type": "omni", "position": [0, 0, 0], "near": 1, "far": 2, "width": 8, "height": 8})",
       "cam.json: key 'type': a camera cannot be an omni light"},
  };
  for (const auto& [text, expected] : cases) {
    Result<Camera> c = parse_camera(text, "cam.json");
    ASSERT_FALSE(c) << text;
    EXPECT_EQ(c.error().message.rfind(expected, 0), 0u) << c.error().message;
  }
}

TEST(Camera, SurfaceDistancesInvertEveryDepthEncoding) {
  for (const char* encoding : {"window", "linear", "radial"}) {
    Result<Camera> c = parse_camera(
        std::string(R"({"position": [1, 2, 3], "direction": [0.2, -0.3, -1], "up": [0, 1, 0],
            "fov_y_deg": 60, "near": 0.5, "far": 40, "width": 5, "height": 4, "depth": ")") +
            encoding + "\"}",
        "cam.json");
    ASSERT_TRUE(c) << c.error().message;
    // Depths of the points at distance t = 3 + col + row along each pixel ray.
    std::vector<float> depth;
    std::vector<double> expected;
    for (int row = 0; row < 4; ++row)
      for (int col = 0; col < 5; ++col) {
        const double t = 3.0 + col + row;
        const Ray ray = pixel_ray(*c, col, row);
        const Vec3d eye = c->view.view.transform_point(ray.origin + t * ray.direction);
        double d = t;
        if (std::string(encoding) == "linear") d = -eye.z;
        if (std::string(encoding) == "window")
          d = 0.5 * c->view.projection.transform_point(eye).z + 0.5;
        depth.push_back(static_cast<float>(d));
        expected.push_back(t);
      }
    depth.back() = std::string(encoding) == "window" ? 1.0f : 40.0f;  // nothing hit
    expected.back() = std::numeric_limits<double>::infinity();
    Result<std::vector<double>> t = surface_distances(*c, depth, 5, 4, "d.exr");
    ASSERT_TRUE(t) << t.error().message;
    for (std::size_t i = 0; i + 1 < expected.size(); ++i)
      EXPECT_NEAR((*t)[i], expected[i], std::string(encoding) == "window" ? 2e-4 : 2e-5)
          << encoding << " pixel " << i;
    EXPECT_TRUE(std::isinf(t->back())) << encoding;
    Result<std::vector<double>> wrong = surface_distances(*c, depth, 4, 5, "d.exr");
    ASSERT_FALSE(wrong);
    EXPECT_EQ(wrong.error().message, "d.exr: camera depth image is 4x5 but the camera is 5x4");
  }
}

}  // namespace
}  // namespace lightvol
