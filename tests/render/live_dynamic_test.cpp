// A live volume in a scene that moves (issue 23, "dynamic"): Sponza (the bundled crop, data/) with
// a box moving through the light across frames. Each frame the GPU renders the shadow map into a
// depth texture (ShadowMapRenderer::draw: the atrium, then the box moved by its model matrix),
// the live volumes (static, and adaptive at E = 0.01) are made from that texture and drawn; the
// test alone reads the map back, builds its volumes on the CPU (static; the quadtree at the same
// E) and draws them: each live airlight must be within 0.5 % relative L2 of its CPU volume's, and
// between frames the map changes only where the box was or is, and the airlight changes.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/airlight/airlight.h>
#include <lightvol/render/gl_volume.h>
#include <lightvol/render/live_volume.h>
#include <lightvol/render/reference.h>
#include <lightvol/scene/scene.h>
#include <lightvol/scene/shadowmap.h>
#include <lightvol/volume/adaptive_volume.h>
#include <lightvol/volume/static_volume.h>

#include "support/gl_test_context.h"

namespace lightvol {
namespace {

using namespace gl;

std::string data(const std::string& name) {
  return std::string(LIGHTVOL_SOURCE_DIR) + "/data/" + name;
}

// A cube of side `side` centred on the origin, outward (the winding does not matter to a depth
// pass).
Mesh cube(float side) {
  Mesh m;
  const float h = side / 2;
  for (int i = 0; i < 8; ++i)
    for (float c : {(i & 1) ? h : -h, (i & 2) ? h : -h, (i & 4) ? h : -h}) m.positions.push_back(c);
  m.indices = {0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
               2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5};
  return m;
}

Mat4d translation(Vec3d t) {
  Mat4d m;
  m(0, 3) = t.x;
  m(1, 3) = t.y;
  m(2, 3) = t.z;
  return m;
}

// Live against the CPU's volume of the same map, drawn by the same passes (the static tests
// measure 1e-5 and below); the bound.
constexpr double kFrameTolerance = 5e-3;

TEST(LiveDynamic, ABoxMovingThroughTheLightOfSponza) {
  REQUIRE_GL_CONTEXT();
  Result<Mesh> atrium = load_scene(data("sponza_crop.ply"));
  ASSERT_TRUE(atrium) << atrium.error().message;
  Result<Light> light = load_light(data("sponza_spot.json"));
  ASSERT_TRUE(light) << light.error().message;
  Result<Medium> medium = load_medium(data("sponza_medium.json"));
  ASSERT_TRUE(medium) << medium.error().message;
  Result<Camera> camera = load_camera(data("sponza_camera.json"));
  ASSERT_TRUE(camera) << camera.error().message;
  camera->width = 160;  // the camera's 4:3 at a test's size
  camera->height = 120;
  const int w = camera->width, h = camera->height;

  Result<ShadowMapRenderer> atrium_pass = ShadowMapRenderer::create(*atrium);
  ASSERT_TRUE(atrium_pass) << atrium_pass.error().message;
  Result<ShadowMapRenderer> box_pass = ShadowMapRenderer::create(cube(1.2f));
  ASSERT_TRUE(box_pass) << box_pass.error().message;
  constexpr int kMap = 256;
  Result<Framebuffer> shadow = Framebuffer::create(kMap, kMap, {}, true);
  Result<Framebuffer> box_only = Framebuffer::create(kMap, kMap, {}, true);
  Result<Framebuffer> view = Framebuffer::create(w, h, {}, true);
  ASSERT_TRUE(shadow && box_only && view);

  Result<std::unique_ptr<LiveVolume>> live =
      LiveVolume::create(*light, {shadow->depth_texture(), kMap, kMap});
  ASSERT_TRUE(live) << live.error().message;
  constexpr double kMaxError = 0.01;  // the Sponza table's adaptive bound
  LiveOptions adaptive_options;
  adaptive_options.max_error = kMaxError;
  Result<std::unique_ptr<LiveVolume>> live_adaptive =
      LiveVolume::create(*light, {shadow->depth_texture(), kMap, kMap}, adaptive_options);
  ASSERT_TRUE(live_adaptive) << live_adaptive.error().message;
  RenderScene scene{*camera, std::vector<double>(static_cast<std::size_t>(w) * h, INFINITY), *light,
                    *medium};
  Result<std::unique_ptr<GlVolumeRenderer>> renderer = GlVolumeRenderer::create(scene);
  ASSERT_TRUE(renderer) << renderer.error().message;

  // The box 5 units down the light's axis, moving across it along x.
  const Vec3d on_axis = light->position + 5.0 * normalize(light->direction);
  std::vector<float> previous_map, previous_box;
  Image previous, previous_adaptive;
  for (int frame = 0; frame < 3; ++frame) {
    const Mat4d model = translation(on_axis + Vec3d{-1.2 + 1.2 * frame, 0, 0});
    // The frame, on the GPU: the shadow map with the box, the camera's depth with the box.
    shadow->bind();
    glClearDepth(1.0);
    glClear(GL_DEPTH_BUFFER_BIT);
    atrium_pass->draw(*light, 0);
    box_pass->draw(*light, 0, model);
    view->bind();
    glClear(GL_DEPTH_BUFFER_BIT);
    atrium_pass->draw(camera->view, 0);
    box_pass->draw(camera->view, 0, model);
    Result<std::vector<double>> surface =
        surface_distances(*camera, view->read(-1, 1), w, h, "camera");
    ASSERT_TRUE(surface) << surface.error().message;
    scene.surface = std::move(*surface);
    const TextureHandle surface_texture = make_surface_texture(scene);
    ASSERT_TRUE((*renderer)->set_surface(surface_texture.id()));
    ASSERT_TRUE((*renderer)->set_volume(**live));
    const Image airlight = (*renderer)->render();
    ASSERT_TRUE((*renderer)->set_volume(**live_adaptive));
    const Image airlight_adaptive = (*renderer)->render();

    // The check: the map read back, its volume built on the CPU and drawn the same way.
    DepthImage map{kMap, kMap, shadow->read(-1, 1)};  // first row = top, as files store it
    Result<Mesh> built = build_static_volume(*light, map, {}, "frame " + std::to_string(frame));
    ASSERT_TRUE(built) << built.error().message;
    (*renderer)->set_volume(*built);
    const Image expected = (*renderer)->render();
    const ImageDifference d = compare_images(airlight, expected);
    AdaptiveOptions quadtree;
    quadtree.tessellation = Tessellation::quadtree;
    quadtree.max_error = kMaxError;
    Result<Mesh> built_adaptive =
        build_adaptive_volume(*light, map, {}, quadtree, "frame " + std::to_string(frame), nullptr);
    ASSERT_TRUE(built_adaptive) << built_adaptive.error().message;
    (*renderer)->set_volume(*built_adaptive);
    const ImageDifference d_adaptive = compare_images(airlight_adaptive, (*renderer)->render());
    double total = 0;
    for (double v : expected.values) total += v;
    box_only->bind();
    glClear(GL_DEPTH_BUFFER_BIT);
    box_pass->draw(*light, 0, model);
    const std::vector<float> box = box_only->read(-1, 1);
    const std::size_t box_texels = static_cast<std::size_t>(
        std::count_if(box.begin(), box.end(), [](float z) { return z < 1; }));
    std::printf(
        "  frame %d: box on %zu texels; live against the CPU's volume: relative L2 %.2e; "
        "adaptive (%zu triangles) %.2e\n",
        frame, box_texels, d.relative_l2, built_adaptive->num_triangles(), d_adaptive.relative_l2);
    EXPECT_GT(total, 0) << frame;
    EXPECT_GT(box_texels, 500u) << frame;  // the box is in the light
    EXPECT_LE(d.relative_l2, kFrameTolerance) << frame;
    EXPECT_LE(d_adaptive.relative_l2, kFrameTolerance) << frame;
    EXPECT_LT(built_adaptive->num_triangles(), built->num_triangles() / 4) << frame;

    if (frame > 0) {
      // The map changed, and only where the box was or is; so did the airlight.
      std::size_t changed = 0, elsewhere = 0;
      for (std::size_t i = 0; i < map.values.size(); ++i) {
        if (map.values[i] == previous_map[i]) continue;
        ++changed;
        if (box[i] == 1 && previous_box[i] == 1) ++elsewhere;
      }
      const double moved = compare_images(airlight, previous).relative_l2;
      const double moved_adaptive =
          compare_images(airlight_adaptive, previous_adaptive).relative_l2;
      std::printf(
          "  frame %d against %d: %zu texels changed (%zu away from the box), airlight "
          "%.2e\n",
          frame, frame - 1, changed, elsewhere, moved);
      EXPECT_GT(changed, 500u);
      EXPECT_EQ(elsewhere, 0u);
      EXPECT_GT(moved, 0.01);
      EXPECT_GT(moved_adaptive, 0.01);
    }
    previous_map = map.values.to_vector();
    previous_box = box;
    previous = airlight;
    previous_adaptive = airlight_adaptive;
  }
  EXPECT_EQ(pending_error(), "");
}

}  // namespace
}  // namespace lightvol
