// Ray marching converges to the volume's exact airlight as the step count grows; interleaved
// sampling with the gather helps at a fixed count; omni maps work; the radial blur is
// the blur computed on the CPU.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

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
    const RenderScene scene = test::make_render_scene(
        test::make_camera({6, 3, 6}, {0, 1, 0}, kW, kH), light, test::render_test_medium(0.3));
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
  const RenderScene scene = test::make_render_scene(
      test::make_camera({5, 1.5, 4}, {0, 1, 0}, kW, kH), light, test::render_test_medium(0.3));
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

// The radial blur on the CPU, as gl_marchers.h describes it (Mitchell 2007), in OpenGL's rows
// (first row at the bottom) and in float as the shader computes it: the occlusion pre-pass (the
// unshadowed glow σs·I·p(θ)·e^(−σt·D)/max(h, D/50) where the visible surface lies beyond the
// light, 0 elsewhere), then `samples` taps along the line toward the light's screen position,
// each weighted by 1/samples and decayed.
Image cpu_radial(const RenderScene& scene, const MarchOptions& o) {
  const Camera& cam = scene.camera;
  const int w = cam.width, h = cam.height;
  EXPECT_FALSE(cam.view.flip_y);
  const Vec3d light = scene.light.position;
  std::vector<float> occlusion(static_cast<std::size_t>(w) * h);
  for (int row = 0; row < h; ++row)
    for (int col = 0; col < w; ++col) {
      const Ray ray = pixel_ray(cam, col, row);
      const Vec3d to_light = light - ray.origin;
      const double dist = length(to_light);
      const double hd =
          std::max(length(cross(ray.direction, to_light)), 1e-6 * std::max(1.0, dist));
      const Medium& m = scene.medium;
      const double glow = m.scattering * m.intensity *
                          m.phase(dot(ray.direction, to_light) / dist) *
                          std::exp(-m.extinction() * dist) / std::max(hd, 0.02 * dist);
      const std::size_t i = static_cast<std::size_t>(row) * w + col;
      occlusion[static_cast<std::size_t>(h - 1 - row) * w + col] =  // OpenGL's rows
          scene.surface[i] > dist ? static_cast<float>(glow) : 0.0f;
    }
  const Vec3d ndc = (cam.view.projection * cam.view.view).transform_point(light);
  const float light_u = static_cast<float>(0.5 * ndc.x + 0.5);
  const float light_v = static_cast<float>(0.5 * ndc.y + 0.5);
  const float weight = 1.0f / static_cast<float>(o.samples);
  Image out;
  out.width = w;
  out.height = h;
  out.values.assign(static_cast<std::size_t>(w) * h, 0.0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float u = (static_cast<float>(x) + 0.5f) / static_cast<float>(w);
      float v = (static_cast<float>(y) + 0.5f) / static_cast<float>(h);
      const float du =
          (u - light_u) * static_cast<float>(o.density) / static_cast<float>(o.samples);
      const float dv =
          (v - light_v) * static_cast<float>(o.density) / static_cast<float>(o.samples);
      float decay = 1.0f, sum = 0.0f;
      for (int i = 0; i < o.samples; ++i) {
        u -= du;
        v -= dv;
        const int qx = std::clamp(static_cast<int>(u * static_cast<float>(w)), 0, w - 1);
        const int qy = std::clamp(static_cast<int>(v * static_cast<float>(h)), 0, h - 1);
        sum += occlusion[static_cast<std::size_t>(qy) * w + qx] * decay * weight;
        decay *= static_cast<float>(o.decay);
      }
      out.values[static_cast<std::size_t>(h - 1 - y) * w + x] =
          sum * static_cast<float>(o.exposure);
    }
  return out;
}

TEST(GlRadial, MatchesTheBlurComputedOnTheCpu) {
  REQUIRE_GL_CONTEXT();
  const Light light = test::light_from_json(test::spot_json("linear"));
  // Looking at the light from below, past the box: the light is on screen.
  const RenderScene scene = test::make_render_scene(test::make_camera({4, 1, 4}, {0, 4, 0}, kW, kH),
                                                    light, test::render_test_medium(0.3));
  MarchOptions o;
  o.method = MarchMethod::radial;
  Result<std::unique_ptr<GlMarcher>> m = GlMarcher::create(scene, {}, {}, o);
  ASSERT_TRUE(m) << m.error().message;
  const Image image = (*m)->render();
  const Image cpu = cpu_radial(scene, o);
  double peak = 0;
  for (double v : cpu.values) peak = std::max(peak, v);
  ASSERT_GT(peak, 0);  // the glow is on screen
  const ImageDifference d = compare_images(image, cpu);
  std::printf("  radial vs CPU: relative L2 %.2e, max abs %.2e (peak %.3e)\n", d.relative_l2,
              d.max_abs, peak);
  EXPECT_LT(d.relative_l2, 1e-5);  // measured 2.4e-07: float rounding (llvmpipe against GCC)
}

TEST(GlRaymarch, RejectsTheWrongNumberOfMaps) {
  REQUIRE_GL_CONTEXT();
  const Light light = test::light_from_json(test::spot_json("linear"));
  const RenderScene scene = test::make_render_scene(test::make_camera({6, 3, 6}, {0, 1, 0}, 8, 6),
                                                    light, test::render_test_medium(0.3));
  const DepthImage map = test::scene_shadow_map(light, 8, 8);
  Result<std::unique_ptr<GlMarcher>> m = GlMarcher::create(scene, {map, map}, {"a", "b"}, {});
  ASSERT_FALSE(m);
  EXPECT_EQ(m.error().message, "raymarch: a spot light takes 1 shadow map(s), got 2");
}

}  // namespace
}  // namespace lightvol
