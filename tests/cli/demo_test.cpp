// `lightvol demo` end to end at a reduced size: every output is written and both volumes are
// closed, oriented and of the expected size, and the airlight images match the CPU reference.
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/airlight/airlight.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/io/mesh_reader.h>
#include <lightvol/light/light.h>
#include <lightvol/render/image_io.h>
#include <lightvol/render/reference.h>

#include "support/gl_test_context.h"
#include "support/test_support.h"

namespace lightvol {
namespace {

TEST(Demo, RunsOnTheBundledSceneAtSize64) {
  test::TempDir dir;
  const test::CommandResult r = test::run_lightvol("demo --out " + dir.path() + " --size 64");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The summary names every step.
  for (const char* step : {"shadow map 64x64", "static volume", "adaptive volume", "check static",
                           "check adaptive", "fog picture"})
    EXPECT_NE(r.out.find(step), std::string::npos) << step << "\n" << r.out;
  EXPECT_EQ(r.out.find("INVALID"), std::string::npos) << r.out;

  Result<DepthImage> shadow = read_depth_image(dir.file("shadow_map.exr"));
  ASSERT_TRUE(shadow) << shadow.error().message;
  EXPECT_EQ(shadow->width, 64);
  EXPECT_EQ(shadow->height, 64);
  int hits = 0;
  for (const float d : shadow->values) hits += d < 1.0f ? 1 : 0;
  // The light's 85° cone sees surfaces everywhere but at two corners, which look out of the crop's
  // open ends (it keeps |x| <= 6 of the atrium): 62 texels there are the far plane.
  EXPECT_EQ(hits, 64 * 64 - 62);
  Result<DepthImage> camera = read_depth_image(dir.file("camera_depth.exr"));
  ASSERT_TRUE(camera);
  EXPECT_EQ(camera->width, 60);  // 480 × 64/512
  EXPECT_EQ(camera->height, 45);

  Result<Mesh> fixed = read_mesh(dir.file("volume_static.ply"));
  ASSERT_TRUE(fixed) << fixed.error().message;
  EXPECT_EQ(fixed->num_triangles(), 2u * 64 * 64 - 2);
  EXPECT_TRUE(test::is_closed_and_oriented(*fixed));
  Result<Mesh> adaptive = read_mesh(dir.file("volume_adaptive.ply"));
  ASSERT_TRUE(adaptive) << adaptive.error().message;
  EXPECT_LT(adaptive->num_triangles(), fixed->num_triangles());
  EXPECT_TRUE(test::is_closed_and_oriented(*adaptive));
  EXPECT_GT(signed_volume(*adaptive), 0);

  // What the web viewer needs: the volumes as GLBs (the same meshes), the scene, camera, medium,
  // and the command that serves them.
  for (const char* name : {"volume_static", "volume_adaptive"}) {
    Result<Mesh> ply = read_mesh(dir.file(std::string(name) + ".ply"));
    Result<Mesh> glb = read_mesh(dir.file(std::string(name) + ".glb"));
    ASSERT_TRUE(ply && glb) << name;
    EXPECT_EQ(glb->positions, ply->positions) << name;
    EXPECT_EQ(glb->indices, ply->indices) << name;
  }
  Result<Mesh> scene = read_mesh(dir.file("scene.glb"));
  ASSERT_TRUE(scene) << scene.error().message;
  EXPECT_EQ(scene->num_triangles(), 27336u);
  Result<Camera> viewer_camera = load_camera(dir.file("camera.json"));
  ASSERT_TRUE(viewer_camera) << viewer_camera.error().message;
  EXPECT_EQ(viewer_camera->width, 60);
  EXPECT_EQ(viewer_camera->height, 45);
  EXPECT_TRUE(load_medium(dir.file("medium.json")).ok());
  EXPECT_NE(r.out.find("web/serve.mjs " + dir.path()), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("web/index.html?volume=/data/volume_static.glb"), std::string::npos)
      << r.out;
  // The live page's light: the demo's own spot.
  Result<Light> live_light = load_light(dir.file("light.json"));
  ASSERT_TRUE(live_light) << live_light.error().message;
  EXPECT_EQ(live_light->type, LightType::spot);
  EXPECT_NE(r.out.find("web/live.html?scene=/data/scene.glb&light=/data/light.json"),
            std::string::npos)
      << r.out;

  for (const char* png : {"shadow_map.png", "camera_depth.png", "demo_fog.png"})
    EXPECT_TRUE(std::filesystem::exists(dir.file(png))) << png;
  REQUIRE_GL_CONTEXT();  // without OpenGL the demo skips rendering
  // The airlight images against the CPU reference (double precision) of the static volume, in the
  // demo's camera, depth, light and medium. Measured relative L2: static 6.5e-06 (float rounding),
  // adaptive 3.6e-02 (its 0.01 error bound), ray marching 2.6e-01 (128 steps and the 2×2 gather's
  // blur at 60×45 pixels); the bounds leave a margin.
  Result<Light> light =
      load_light(std::string(LIGHTVOL_SOURCE_DIR) + "/data/sponza_demo_spot.json");
  Result<Medium> medium = load_medium(dir.file("medium.json"));
  ASSERT_TRUE(light && medium);
  Result<std::vector<double>> surface = surface_distances(
      *viewer_camera, camera->values, camera->width, camera->height, "camera_depth.exr");
  ASSERT_TRUE(surface) << surface.error().message;
  const RenderScene render_scene{*viewer_camera, *surface, *light, *medium};
  const Image reference = render_reference(*fixed, render_scene);
  double mean = 0;
  for (const double v : reference.values) mean += v / static_cast<double>(reference.values.size());
  EXPECT_GT(mean, 0);  // the camera sees the lit shafts
  const struct {
    const char* name;
    double bound;
  } renders[] = {
      {"airlight_static", 1e-4}, {"airlight_adaptive", 0.05}, {"airlight_raymarch", 0.3}};
  for (const auto& [name, bound] : renders) {
    EXPECT_TRUE(std::filesystem::exists(dir.file(std::string(name) + ".png"))) << name;
    Result<Image> image = read_image(dir.file(std::string(name) + ".exr"));
    ASSERT_TRUE(image) << name;
    EXPECT_EQ(image->width, 60);
    const double e = compare_images(*image, reference).relative_l2;
    std::printf("  %s vs the CPU reference: relative L2 %.2e\n", name, e);
    EXPECT_LT(e, bound) << name;
  }
}

}  // namespace
}  // namespace lightvol
