// The adaptive live volume (LiveOptions::max_error; render/live_adaptive.h): the compute passes
// make build's quadtree (`--adaptive --tessellation quadtree`) at the same bound, triangle for
// triangle (omni: build_adaptive_omni_volume's, seam rounds and seams included); the read-back
// volume is closed, passes the light check and meets the bound at every texel (rays cast against
// it); it draws the CPU-built volume's airlight; bad options are refused.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/check/check.h>
#include <lightvol/render/gl_volume.h>
#include <lightvol/render/live_adaptive.h>
#include <lightvol/render/live_volume.h>
#include <lightvol/tessellate/adaptive_grid.h>
#include <lightvol/volume/adaptive_volume.h>
#include <lightvol/volume/omni_adaptive.h>

#include "support/adaptive_support.h"
#include "support/analytic_scene.h"
#include "support/gl_test_context.h"
#include "support/omni_scene.h"
#include "support/test_support.h"

namespace lightvol {
namespace {

using namespace gl;

// `linear` (a linear-depth map of `light_linear`) as the window depth of the same light's
// projection, rounded to float as a depth pass stores it.
DepthImage to_window(const Light& light, const DepthImage& linear) {
  DepthImage map = linear;
  const Mat4d& p = light.projection;
  for (float& d : map.values) {
    const double z = -static_cast<double>(d);
    const double ndc = (p(2, 2) * z + p(2, 3)) / (p(3, 2) * z + p(3, 3));
    d = static_cast<float>(std::clamp(0.5 * ndc + 0.5, 0.0, 1.0));
  }
  return map;
}

// tests/tessellate/adaptive_grid_test.cpp's plateaus whose fix-up rounds cascade across the
// map, one level-3 cell a round (n / 8 − 1 rounds at E = 0.001, directional linear).
DepthImage cascading_steps(int n) {
  return test::make_depth(n, n, [](int c, int r) {
    const int pc = c / 2 * 2, pr = r % 16 / 2 * 2;
    if (pc < 2) return 0.7f;
    if (pc % 8 == 0 && pr == 4) return 0.5009f;
    if (pc % 8 == 2 && pr == 2) return 0.4996f;
    return 0.5f;
  });
}

struct Case {
  std::string name;
  Light light;
  DepthImage map;
};

Light with(const std::string& json, DepthEncoding encoding, bool flip_y) {
  Light light = test::light_from_json(json);
  light.depth = encoding;
  light.flip_y = flip_y;
  return light;
}

// The adaptive tests' scenes (sloped floor, boxes, one-texel bars, a sphere): every level of the
// quadtree, fix-up rounds, clipped cells on maps whose sides are not 2^k + 1.
std::vector<Case> cases() {
  std::vector<Case> out;
  const std::string spot = test::spot_json("linear"), dir = test::directional_json("linear");
  const auto add = [&](const std::string& name, const std::string& json, DepthEncoding e,
                       bool flip_y, const DepthImage& linear) {
    const Light light = with(json, e, flip_y);
    out.push_back({name, light, e == DepthEncoding::window ? to_window(light, linear) : linear});
  };
  add("spot linear 65x65", spot, DepthEncoding::linear, false, test::adaptive_scene(65, 65, 8.0));
  add("spot window 97x81", spot, DepthEncoding::window, false, test::adaptive_scene(97, 81, 8.0));
  add("spot linear 40x96 flip_y", test::spot_json("linear", 40.0 / 96), DepthEncoding::linear, true,
      test::adaptive_scene(40, 96, 6.0));
  add("directional linear 97x81", dir, DepthEncoding::linear, false,
      test::adaptive_scene(97, 81, 7.0));
  add("directional window 64x33 flip_y", dir, DepthEncoding::window, true,
      test::adaptive_scene(64, 33, 7.0));
  {
    const Light light = test::light_from_json(test::spot_json("window"));
    out.push_back({"spot window scene 65x65", light, test::window_scene(65, 65)});
  }
  {
    const Light light = test::light_from_json(test::directional_json("linear"));
    out.push_back({"directional cascading steps 96x96", light, cascading_steps(96)});
  }
  return out;
}

// The CPU's quadtree volume at `e` (build --adaptive --tessellation quadtree).
Mesh cpu_volume(const Case& c, double e, AdaptiveReport* report) {
  AdaptiveOptions o;
  o.tessellation = Tessellation::quadtree;
  o.max_error = e;
  Result<Mesh> mesh = build_adaptive_volume(c.light, c.map, {}, o, "map", report);
  EXPECT_TRUE(mesh) << mesh.error().message;
  return mesh ? std::move(*mesh) : Mesh{};
}

// The CPU quadtree's grid at `e`.
AdaptiveGrid cpu_grid(const Case& c, double e) {
  Result<TexelDepths> texels = TexelDepths::create(c.light, c.map, 0, "map");
  EXPECT_TRUE(texels) << texels.error().message;
  const RefinementPyramid pyramid(std::move(*texels), Refinement::max_error);
  const bool standard =
      Unprojector(c.light, c.map.width, c.map.height, 0, Space::world).standard_winding();
  return pyramid.tessellate(e, standard);
}

// Triangles as sorted lists of vertex-index triples, each rotated to start at its smallest index
// (the winding kept).
std::vector<std::array<std::uint32_t, 3>> triangle_set(const std::vector<std::uint32_t>& idx,
                                                       std::size_t count) {
  std::vector<std::array<std::uint32_t, 3>> out;
  for (std::size_t t = 0; t < count; ++t) {
    std::array<std::uint32_t, 3> a = {idx[3 * t], idx[3 * t + 1], idx[3 * t + 2]};
    std::rotate(a.begin(), std::min_element(a.begin(), a.end()), a.end());
    out.push_back(a);
  }
  std::sort(out.begin(), out.end());
  return out;
}

struct Live {
  TextureHandle texture;
  std::unique_ptr<LiveVolume> volume;
};

Live make_live(const Case& c, double e) {
  Live live;
  live.texture = upload_shadow_map(c.light, c.map);
  LiveOptions options;
  options.max_error = e;
  Result<std::unique_ptr<LiveVolume>> made =
      LiveVolume::create(c.light, {live.texture.id(), c.map.width, c.map.height}, options);
  EXPECT_TRUE(made) << made.error().message;
  if (made) live.volume = std::move(*made);
  return live;
}

// Bounds relative to each scene's own depth range: coarse, medium, fine.
std::vector<double> bounds(const Case& c) {
  if (c.name.find("cascading") != std::string::npos) return {0.001};
  return c.light.depth == DepthEncoding::window && c.light.type == LightType::spot
             ? std::vector<double>{0.2, 0.02, 0.002}
             : std::vector<double>{0.5, 0.05, 0.005};
}

TEST(LiveAdaptive, MakesBuildsQuadtreeTriangleForTriangle) {
  REQUIRE_GL_CONTEXT();
  for (const Case& c : cases()) {
    for (const double e : bounds(c)) {
      SCOPED_TRACE(c.name + " E = " + std::to_string(e));
      const AdaptiveGrid grid = cpu_grid(c, e);
      AdaptiveReport report;
      const Mesh cpu = cpu_volume(c, e, &report);
      Live live = make_live(c, e);
      ASSERT_TRUE(live.volume);
      Result<LiveMesh> gpu = live.volume->read_mesh();
      ASSERT_TRUE(gpu) << gpu.error().message;
      std::printf("  %-32s E %-6g triangles GPU %zu CPU %zu, fix-up rounds %d/%d\n", c.name.c_str(),
                  e, gpu->mesh.num_triangles(), cpu.num_triangles(), gpu->fixup_rounds,
                  grid.fixup_rounds);
      EXPECT_TRUE(gpu->converged);
      EXPECT_EQ(gpu->fixup_rounds, grid.fixup_rounds);
      EXPECT_EQ(gpu->grid_triangles, grid.num_triangles());
      EXPECT_EQ(gpu->vertex_texels, grid.vertices);
      ASSERT_EQ(gpu->mesh.num_vertices(), cpu.num_vertices());
      ASSERT_EQ(gpu->mesh.num_triangles(), cpu.num_triangles());
      // The same triangles over the same vertices (both number the grid's vertices in texel
      // order, then the closing's).
      EXPECT_TRUE(triangle_set(gpu->mesh.indices, gpu->grid_triangles) ==
                  triangle_set(grid.indices, grid.num_triangles()));
      EXPECT_TRUE(triangle_set(gpu->mesh.indices, gpu->mesh.num_triangles()) ==
                  triangle_set(cpu.indices, cpu.num_triangles()));
      // Positions: float on the GPU against double rounded to float (live_volume.h).
      double scale = 0, worst = 0;
      for (std::size_t i = 0; i < cpu.positions.size(); ++i) {
        scale = std::max(scale, static_cast<double>(std::abs(cpu.positions[i])));
        worst = std::max(worst,
                         static_cast<double>(std::abs(gpu->mesh.positions[i] - cpu.positions[i])));
      }
      EXPECT_LE(worst, 2e-6 * scale);
    }
  }
}

TEST(LiveAdaptive, IsClosedPassesTheLightCheckAndMeetsTheBoundAtEveryTexel) {
  REQUIRE_GL_CONTEXT();
  for (const Case& c : cases()) {
    for (const double e : bounds(c)) {
      SCOPED_TRACE(c.name + " E = " + std::to_string(e));
      Live live = make_live(c, e);
      ASSERT_TRUE(live.volume);
      Result<LiveMesh> gpu = live.volume->read_mesh();
      ASSERT_TRUE(gpu) << gpu.error().message;
      const CheckReport check = check_volume_linear(gpu->mesh, &c.light);
      EXPECT_TRUE(check.valid()) << check.first_failure();
      EXPECT_NE(check.proof, NestingProof::none);
      // Every texel's ray cast against the volume (tests/support/adaptive_support.h), with the
      // adaptive volume tests' allowance for float positions.
      const test::RayErrors r = test::ray_errors(gpu->mesh, c.light, c.map);
      EXPECT_EQ(r.missed, 0);
      EXPECT_LE(r.max_error, e * (1 + 1e-4) + 5e-5);
    }
  }
}

TEST(LiveAdaptive, FollowsTheMapFromFrameToFrame) {
  REQUIRE_GL_CONTEXT();
  const Light light = test::light_from_json(test::spot_json("linear"));
  const DepthImage first = test::adaptive_scene(65, 65, 8.0);
  DepthImage second = first;
  for (int r = 10; r < 20; ++r)
    for (int col = 40; col < 55; ++col) second.values[static_cast<std::size_t>(r) * 65 + col] = 3;
  const Case a{"first", light, first}, b{"second", light, second};
  Live live = make_live(a, 0.05);
  ASSERT_TRUE(live.volume);
  Result<LiveMesh> one = live.volume->read_mesh();
  ASSERT_TRUE(one) << one.error().message;
  // The same texture, new contents: no call to the live volume.
  const TextureHandle replacement = upload_shadow_map(light, second);
  std::vector<float> rows(second.values.size());
  for (int t = 0; t < 65; ++t)
    std::copy_n(second.values.begin() + (64 - t) * 65, 65, rows.begin() + t * 65);
  glBindTexture(GL_TEXTURE_2D, live.texture.id());
  glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, 65, 65, GL_RED, GL_FLOAT, rows.data());
  glBindTexture(GL_TEXTURE_2D, 0);
  Result<LiveMesh> two = live.volume->read_mesh();
  ASSERT_TRUE(two) << two.error().message;
  EXPECT_EQ(two->grid_triangles, cpu_grid(b, 0.05).num_triangles());
  EXPECT_NE(two->grid_triangles, one->grid_triangles);
  EXPECT_EQ(one->grid_triangles, cpu_grid(a, 0.05).num_triangles());
}

TEST(LiveAdaptive, SaysWhenTheRoundsAllowedDoNotConverge) {
  REQUIRE_GL_CONTEXT();
  const Case c{"steps", test::light_from_json(test::directional_json("linear")),
               cascading_steps(96)};
  EXPECT_EQ(cpu_grid(c, 0.001).fixup_rounds, 11);
  const TextureHandle texture = upload_shadow_map(c.light, c.map);
  for (const int rounds : {11, 12}) {
    LiveOptions options;
    options.max_error = 0.001;
    options.max_rounds = rounds;
    Result<std::unique_ptr<LiveVolume>> live =
        LiveVolume::create(c.light, {texture.id(), 96, 96}, options);
    ASSERT_TRUE(live) << live.error().message;
    Result<LiveMesh> gpu = (*live)->read_mesh();
    ASSERT_TRUE(gpu) << gpu.error().message;
    // 11 rounds split; the 12th finds nothing more to split (converged).
    EXPECT_EQ(gpu->fixup_rounds, 11) << rounds;
    EXPECT_EQ(gpu->converged, rounds == 12) << rounds;
  }
}

TEST(LiveAdaptive, DrawsTheAirlightOfTheCpuBuiltAdaptiveVolume) {
  REQUIRE_GL_CONTEXT();
  const test::Box box{{-0.7, 1.0, -0.9}, {0.2, 1.5, 0.1}};
  const std::vector<test::LightViewCase> image_cases = test::light_view_cases();
  for (const test::LightViewCase& ic : image_cases) {
    SCOPED_TRACE(ic.name);
    const Light light = with(ic.json, ic.encoding, false);
    Light linear = light;
    linear.depth = DepthEncoding::linear;
    const DepthImage linear_map = test::scene_shadow_map(linear, 96, 80, box);
    const Case c{ic.name, light,
                 ic.encoding == DepthEncoding::window ? to_window(light, linear_map) : linear_map};
    const RenderScene scene = test::make_render_scene(test::make_camera(ic.eye, ic.target, 64, 48),
                                                      light, test::render_test_medium());
    Result<std::unique_ptr<GlVolumeRenderer>> mesh_renderer = GlVolumeRenderer::create(scene);
    Result<std::unique_ptr<GlVolumeRenderer>> live_renderer = GlVolumeRenderer::create(scene);
    ASSERT_TRUE(mesh_renderer && live_renderer);
    const double e = 0.01;
    AdaptiveReport report;
    (*mesh_renderer)->set_volume(cpu_volume(c, e, &report));
    const Image reference = (*mesh_renderer)->render();
    Live live = make_live(c, e);
    ASSERT_TRUE(live.volume);
    EXPECT_FALSE((*live_renderer)->set_volume(*live.volume, LiveDraw::vertex_stage));
    ASSERT_TRUE((*live_renderer)->set_volume(*live.volume, LiveDraw::two_pass));
    const Image image = (*live_renderer)->render();
    const double l2 = compare_images(image, reference).relative_l2;
    std::printf("  %-28s %zu triangles, relative L2 %.2e\n", ic.name, report.triangles, l2);
    EXPECT_LE(l2, 0.005);
    double sum = 0;
    for (const double v : reference.values) sum += v;
    EXPECT_GT(sum, 0);
  }
}

TEST(LiveAdaptive, RefusesWhatItCannotDo) {
  REQUIRE_GL_CONTEXT();
  const Light spot = test::light_from_json(test::spot_json("linear"));
  const DepthImage map = test::adaptive_scene(33, 33, 8.0);
  const TextureHandle texture = upload_shadow_map(spot, map);
  const GlShadowMap gl_map{texture.id(), 33, 33};
  const auto message = [&](const Light& light, double e, int rounds) {
    LiveOptions o;
    o.max_error = e;
    o.max_rounds = rounds;
    Result<std::unique_ptr<LiveVolume>> live = LiveVolume::create(light, gl_map, o);
    return live ? std::string() : live.error().message;
  };
  EXPECT_EQ(message(spot, -1, 32),
            "live volume: max_error: expected a finite number >= 0, got -1.000000");
  EXPECT_NE(message(spot, std::nan(""), 32).find("max_error: expected a finite number"),
            std::string::npos);
  EXPECT_EQ(message(spot, 0.1, 0), "live volume: max_rounds: expected 1 to 63, got 0");
  {
    LiveOptions o;
    o.max_error = 0.1;
    o.max_seam_rounds = 0;
    Result<std::unique_ptr<LiveVolume>> live = LiveVolume::create(spot, gl_map, o);
    ASSERT_FALSE(live);
    EXPECT_EQ(live.error().message, "live volume: max_seam_rounds: expected 1 to 64, got 0");
  }
  Light radial = spot;
  radial.depth = DepthEncoding::radial;
  EXPECT_NE(message(radial, 0.1, 32).find("the light's \"depth\" is \"radial\""),
            std::string::npos);
  EXPECT_EQ(message(spot, 0.1, 32), "");
}

// The omni cases: the room with a pillar and a ball (tests/support/omni_scene.h) on faces whose
// sides are and are not 2^k + 1, in window depth, and once in linear depth.
struct OmniCase {
  std::string name;
  Light light;
  CubeFaces cube;
};

std::vector<OmniCase> omni_cases() {
  std::vector<OmniCase> out;
  const Light window = test::light_from_json(test::omni_scene_light_json());
  for (const int w : {17, 24, 37})
    out.push_back({"omni window " + std::to_string(w), window, test::omni_scene(w)});
  // The same room in linear depth (eye −z from the window depth, rounded to float).
  Light linear = window;
  linear.depth = DepthEncoding::linear;
  CubeFaces cube = test::omni_scene(24);
  const Mat4d& p = linear.projection;
  for (DepthImage& face : cube.faces)
    for (float& d : face.values) {
      const double ndc = 2.0 * d - 1;
      d = static_cast<float>(-(ndc * p(3, 3) - p(2, 3)) / (p(2, 2) - ndc * p(3, 2)));
    }
  out.push_back({"omni linear 24", linear, cube});
  // flip_y: the same images read bottom row first (other face frames, other seams).
  Light flipped = window;
  flipped.flip_y = true;
  out.push_back({"omni window 24 flip_y", flipped, test::omni_scene(24)});
  // The cascading plateaus on every face (linear depth about 0.5 from the light): fix-up rounds.
  CubeFaces steps;
  for (int f = 0; f < kOmniFaces; ++f) {
    steps.faces[f] = cascading_steps(40);
    steps.sources[f] = omni_face_name(f);
  }
  out.push_back({"omni linear steps 40", linear, steps});
  return out;
}

struct LiveOmni {
  std::vector<TextureHandle> textures;
  std::unique_ptr<LiveVolume> volume;
};

LiveOmni make_live_omni(const OmniCase& c, double e) {
  LiveOmni live;
  std::vector<GlShadowMap> maps;
  for (const DepthImage& face : c.cube.faces) {
    live.textures.push_back(upload_shadow_map(c.light, face));
    maps.push_back({live.textures.back().id(), face.width, face.height});
  }
  LiveOptions options;
  options.max_error = e;
  Result<std::unique_ptr<LiveVolume>> made = LiveVolume::create(c.light, maps, options);
  EXPECT_TRUE(made) << made.error().message;
  if (made) live.volume = std::move(*made);
  return live;
}

Mesh cpu_omni_volume(const OmniCase& c, double e, AdaptiveReport* report,
                     OmniAdaptiveDetail* detail) {
  AdaptiveOptions o;
  o.tessellation = Tessellation::quadtree;
  o.max_error = e;
  Result<Mesh> mesh = build_adaptive_omni_volume(c.light, c.cube, {}, o, report, detail);
  EXPECT_TRUE(mesh) << mesh.error().message;
  return mesh ? std::move(*mesh) : Mesh{};
}

TEST(LiveAdaptive, OmniIsBuildsAdaptiveOmniVolumeTriangleForTriangle) {
  REQUIRE_GL_CONTEXT();
  for (const OmniCase& c : omni_cases()) {
    for (const double e : c.name.find("steps") != std::string::npos
                              ? std::vector<double>{0.001, 0.0003, 0.0001}
                              : std::vector<double>{0.5, 0.05, 0.005, 0.0005}) {
      SCOPED_TRACE(c.name + " E = " + std::to_string(e));
      AdaptiveReport report;
      OmniAdaptiveDetail detail;
      const Mesh cpu = cpu_omni_volume(c, e, &report, &detail);
      LiveOmni live = make_live_omni(c, e);
      ASSERT_TRUE(live.volume);
      Result<LiveMesh> gpu = live.volume->read_mesh();
      ASSERT_TRUE(gpu) << gpu.error().message;
      std::printf("  %-18s E %-6g triangles GPU %zu CPU %zu, seam rounds %d/%d, fix-up %d/%d\n",
                  c.name.c_str(), e, gpu->mesh.num_triangles(), cpu.num_triangles(),
                  gpu->seam_rounds, detail.seam_rounds, gpu->fixup_rounds, report.fixup_rounds);
      EXPECT_TRUE(gpu->converged);
      EXPECT_TRUE(gpu->seams_agree);
      EXPECT_EQ(gpu->seam_rounds, detail.seam_rounds);
      EXPECT_EQ(gpu->fixup_rounds, report.fixup_rounds);
      EXPECT_EQ(gpu->grid_triangles, report.grid_triangles);
      ASSERT_EQ(gpu->mesh.num_vertices(), cpu.num_vertices());
      ASSERT_EQ(gpu->mesh.num_triangles(), cpu.num_triangles());
      // The faces' triangles as sets (each face's vertices in texel order on both sides); the
      // seams and corners in build's order, index for index.
      EXPECT_TRUE(triangle_set(gpu->mesh.indices, gpu->grid_triangles) ==
                  triangle_set(cpu.indices, report.grid_triangles));
      EXPECT_TRUE(std::equal(gpu->mesh.indices.begin() + 3 * report.grid_triangles,
                             gpu->mesh.indices.end(),
                             cpu.indices.begin() + 3 * report.grid_triangles));
      double scale = 0, worst = 0;
      for (std::size_t i = 0; i < cpu.positions.size(); ++i) {
        scale = std::max(scale, static_cast<double>(std::abs(cpu.positions[i])));
        worst = std::max(worst,
                         static_cast<double>(std::abs(gpu->mesh.positions[i] - cpu.positions[i])));
      }
      EXPECT_LE(worst, 2e-6 * scale);
    }
  }
}

// The tessellation's passes run on all six faces in one dispatch where the faces' buffers fit
// one storage block (these maps), else on groups of 3, 2 or 1: the same volume, bit for bit.
TEST(LiveAdaptive, OmniMakesTheSameVolumeWhateverTheFacesPerDispatch) {
  REQUIRE_GL_CONTEXT();
  const std::vector<OmniCase> all = omni_cases();
  // The cascading plateaus on every other face, mirrored on the others: faces that need
  // different numbers of fix-up rounds in one dispatch.
  OmniCase mixed{"omni linear steps 96 mixed", all[5].light, {}};
  for (int f = 0; f < kOmniFaces; ++f) {
    DepthImage map = cascading_steps(96);
    if (f % 2 == 1)
      for (int r = 0; r < 96; ++r)
        std::reverse(map.values.begin() + r * 96, map.values.begin() + (r + 1) * 96);
    mixed.cube.faces[f] = map;
    mixed.cube.sources[f] = omni_face_name(f);
  }
  for (const auto& [c, e] : {std::pair<const OmniCase&, double>{all[2], 0.0005},
                             std::pair<const OmniCase&, double>{all[5], 0.001},
                             std::pair<const OmniCase&, double>{mixed, 0.001}}) {
    SCOPED_TRACE(c.name + " E = " + std::to_string(e));
    AdaptiveReport report;
    OmniAdaptiveDetail detail;
    const Mesh cpu = cpu_omni_volume(c, e, &report, &detail);
    LiveOmni live = make_live_omni(c, e);
    ASSERT_TRUE(live.volume);
    Result<LiveMesh> expected = live.volume->read_mesh();
    ASSERT_TRUE(expected) << expected.error().message;
    std::printf("  %-26s E %-6g triangles %zu, seam rounds %d, fix-up rounds %d\n", c.name.c_str(),
                e, expected->mesh.num_triangles(), expected->seam_rounds, expected->fixup_rounds);
    EXPECT_GE(expected->seam_rounds, 2);
    EXPECT_EQ(expected->seam_rounds, detail.seam_rounds);
    EXPECT_EQ(expected->fixup_rounds, report.fixup_rounds);
    EXPECT_EQ(expected->mesh.num_triangles(), cpu.num_triangles());
    EXPECT_TRUE(triangle_set(expected->mesh.indices, expected->mesh.num_triangles()) ==
                triangle_set(cpu.indices, cpu.num_triangles()));
    const int w = c.cube.faces[0].width;
    for (const int n : {0, 1, 2, 3, 6}) {
      SCOPED_TRACE("faces per dispatch " + std::to_string(n));
      Result<std::unique_ptr<detail::LiveAdaptive>> passes =
          detail::LiveAdaptive::create(e, LiveOptions{}.max_rounds, LiveOptions{}.max_seam_rounds);
      ASSERT_TRUE(passes) << passes.error().message;
      if (n != 0) (*passes)->set_faces_per_dispatch(n);
      ASSERT_TRUE((*passes)->resize(c.light, w, w));
      EXPECT_EQ((*passes)->faces_per_dispatch(), n == 0 ? 6 : n);
      (*passes)->generate([&](const Program& program) { live.volume->bind(program, 2); });
      Result<LiveMesh> gpu = (*passes)->read_back();
      ASSERT_TRUE(gpu) << gpu.error().message;
      EXPECT_EQ(gpu->seam_rounds, expected->seam_rounds);
      EXPECT_EQ(gpu->fixup_rounds, expected->fixup_rounds);
      EXPECT_EQ(gpu->converged, expected->converged);
      EXPECT_TRUE(gpu->mesh.indices == expected->mesh.indices);
      EXPECT_TRUE(gpu->mesh.positions == expected->mesh.positions);
    }
  }
}

TEST(LiveAdaptive, OmniIsClosedPassesTheLightCheckAndMeetsTheBoundAtEveryTexel) {
  REQUIRE_GL_CONTEXT();
  const std::vector<OmniCase> all = omni_cases();
  for (const OmniCase& c : {all[0], all[3], all[4], all[5]}) {
    for (const double e : {0.05, 0.005, 0.0003}) {
      SCOPED_TRACE(c.name + " E = " + std::to_string(e));
      LiveOmni live = make_live_omni(c, e);
      ASSERT_TRUE(live.volume);
      Result<LiveMesh> gpu = live.volume->read_mesh();
      ASSERT_TRUE(gpu) << gpu.error().message;
      const CheckReport check = check_volume_linear(gpu->mesh, &c.light);
      EXPECT_TRUE(check.valid()) << check.first_failure();
      EXPECT_NE(check.proof, NestingProof::none);
      EXPECT_LE(test::omni_ray_error(gpu->mesh, c.light, c.cube), e * (1 + 1e-4) + 5e-5);
    }
  }
}

TEST(LiveAdaptive, OmniFollowsTheFacesFromFrameToFrame) {
  REQUIRE_GL_CONTEXT();
  const OmniCase first = omni_cases()[1];
  OmniCase second = first;
  // Something close to the light in front of face +X (a corner of its map), between frames.
  DepthImage& face = second.cube.faces[0];
  for (int r = 0; r < 9; ++r)
    for (int col = 15; col < 24; ++col) face.values[static_cast<std::size_t>(r) * 24 + col] = 0.2f;
  LiveOmni live = make_live_omni(first, 0.005);
  ASSERT_TRUE(live.volume);
  Result<LiveMesh> one = live.volume->read_mesh();
  ASSERT_TRUE(one) << one.error().message;
  // The same texture, new contents (GL row t is image row 23 - t): no call to the live volume.
  std::vector<float> rows(face.values.size());
  for (int t = 0; t < 24; ++t)
    std::copy_n(face.values.begin() + (23 - t) * 24, 24, rows.begin() + t * 24);
  glBindTexture(GL_TEXTURE_2D, live.textures[0].id());
  glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, 24, 24, GL_RED, GL_FLOAT, rows.data());
  glBindTexture(GL_TEXTURE_2D, 0);
  Result<LiveMesh> two = live.volume->read_mesh();
  ASSERT_TRUE(two) << two.error().message;
  for (const auto& [c, gpu] : {std::pair<const OmniCase&, const LiveMesh&>{first, *one},
                               std::pair<const OmniCase&, const LiveMesh&>{second, *two}}) {
    AdaptiveReport report;
    OmniAdaptiveDetail detail;
    const Mesh cpu = cpu_omni_volume(c, 0.005, &report, &detail);
    EXPECT_EQ(gpu.mesh.num_triangles(), cpu.num_triangles());
    EXPECT_EQ(gpu.seam_rounds, detail.seam_rounds);
    EXPECT_TRUE(triangle_set(gpu.mesh.indices, gpu.mesh.num_triangles()) ==
                triangle_set(cpu.indices, cpu.num_triangles()));
  }
  EXPECT_NE(one->mesh.num_triangles(), two->mesh.num_triangles());
}

TEST(LiveAdaptive, OmniSeamsStayClosedWhenTheSeamRoundsAllowedDoNotConverge) {
  REQUIRE_GL_CONTEXT();
  const OmniCase c = omni_cases()[2];
  AdaptiveReport report;
  OmniAdaptiveDetail detail;
  cpu_omni_volume(c, 0.005, &report, &detail);
  ASSERT_GE(detail.seam_rounds, 2);
  LiveOmni live = make_live_omni(c, 0.005);
  ASSERT_TRUE(live.volume);
  std::vector<GlShadowMap> maps = live.volume->shadow_maps();
  LiveOptions options;
  options.max_error = 0.005;
  options.max_seam_rounds = 1;
  Result<std::unique_ptr<LiveVolume>> one = LiveVolume::create(c.light, maps, options);
  ASSERT_TRUE(one) << one.error().message;
  Result<LiveMesh> gpu = (*one)->read_mesh();
  ASSERT_TRUE(gpu) << gpu.error().message;
  EXPECT_EQ(gpu->seam_rounds, 1);
  EXPECT_FALSE(gpu->seams_agree);
  EXPECT_FALSE(gpu->converged);
  // Each seam zips its two different borders: still closed and outward.
  const CheckReport check = check_volume_linear(gpu->mesh, &c.light);
  EXPECT_TRUE(check.valid()) << check.first_failure();
}

TEST(LiveAdaptive, OmniDrawsTheAirlightOfTheCpuBuiltAdaptiveVolume) {
  REQUIRE_GL_CONTEXT();
  const OmniCase c = omni_cases()[2];
  const double e = 0.01;
  AdaptiveReport report;
  OmniAdaptiveDetail detail;
  const Mesh cpu = cpu_omni_volume(c, e, &report, &detail);
  LiveOmni live = make_live_omni(c, e);
  ASSERT_TRUE(live.volume);
  // Inside the room, looking past the pillar towards the window; then from the ball's side.
  for (auto [eye, target] :
       {std::pair<Vec3d, Vec3d>{{4, 3, 3}, {-1, 1, -3}}, {{-4, 1, -3}, {2, 2, 2}}}) {
    const RenderScene scene = test::make_render_scene(test::make_camera(eye, target, 64, 48),
                                                      c.light, test::render_test_medium());
    Result<std::unique_ptr<GlVolumeRenderer>> mesh_renderer = GlVolumeRenderer::create(scene);
    Result<std::unique_ptr<GlVolumeRenderer>> live_renderer = GlVolumeRenderer::create(scene);
    ASSERT_TRUE(mesh_renderer && live_renderer);
    (*mesh_renderer)->set_volume(cpu);
    const Image reference = (*mesh_renderer)->render();
    ASSERT_TRUE((*live_renderer)->set_volume(*live.volume, LiveDraw::two_pass));
    const Image image = (*live_renderer)->render();
    const double l2 = compare_images(image, reference).relative_l2;
    std::printf("  omni eye (%g, %g, %g): %zu triangles, relative L2 %.2e\n", eye.x, eye.y, eye.z,
                cpu.num_triangles(), l2);
    EXPECT_LE(l2, 0.005);
    double sum = 0;
    for (const double v : reference.values) sum += v;
    EXPECT_GT(sum, 0);
  }
}

}  // namespace
}  // namespace lightvol
