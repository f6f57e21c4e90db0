// render/airlight_render.h: what `lightvol render` calls around its renderers — the camera's scene
// from its files (and what it refuses), the CPU reference as a timed step, the image's levels and
// its comparison with an image file.
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/depth/depth_image.h>
#include <lightvol/render/airlight_render.h>
#include <lightvol/render/image_io.h>
#include <lightvol/render/reference.h>
#include <lightvol/volume/static_volume.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

constexpr int kW = 16, kH = 12;

// light.json, camera.json (16×12, linear depth), camdepth.exr (every pixel at depth 12: the
// view axis crosses the spot light's cone) and
// medium.json in `dir`; the request naming them.
RenderRequest write_scene(const test::TempDir& dir) {
  RenderRequest r;
  r.light_path = dir.write("light.json", test::spot_json("linear"));
  r.camera_path = dir.write(
      "camera.json",
      R"({"position": [0, 2, 8], "direction": [0, 0, -1], "up": [0, 1, 0], "fov_y_deg": 50,
          "aspect": 1.3333333333333333, "near": 0.05, "far": 100, "depth": "linear",
          "width": 16, "height": 12})");
  r.depth_path = dir.file("camdepth.exr");
  EXPECT_TRUE(write_depth_image(r.depth_path, test::constant_depth(kW, kH, 12.0f)));
  r.medium_path = dir.write(
      "medium.json",
      R"({"scattering": 0.06, "absorption": 0.02, "intensity": 20, "phase": {"type": "hg", "g": 0.3}})");
  return r;
}

TEST(AirlightRender, MethodNamesAndWhichTakeAMesh) {
  EXPECT_STREQ(to_string(RenderMethod::volume), "volume");
  EXPECT_STREQ(to_string(RenderMethod::live), "live");
  EXPECT_STREQ(to_string(RenderMethod::reference), "reference");
  EXPECT_STREQ(to_string(RenderMethod::raymarch), "raymarch");
  EXPECT_STREQ(to_string(RenderMethod::radial), "radial");
  EXPECT_TRUE(method_takes_mesh(RenderMethod::volume));
  EXPECT_TRUE(method_takes_mesh(RenderMethod::reference));
  EXPECT_FALSE(method_takes_mesh(RenderMethod::live));
  EXPECT_FALSE(method_takes_mesh(RenderMethod::raymarch));
  EXPECT_FALSE(method_takes_mesh(RenderMethod::radial));
}

TEST(AirlightRender, SceneFromFilesHasTheCameraDepthAsSurfaceDistancesAndTimesItsRead) {
  const test::TempDir dir;
  const RenderRequest request = write_scene(dir);
  std::vector<std::string> ended;
  StageLog log;
  log.on_end = [&](const StageRecord& s, const std::string& detail) {
    ended.push_back(s.name + ": " + detail);
  };
  Result<RenderScene> scene = load_render_scene(request, log);
  ASSERT_TRUE(scene) << scene.error().message;
  EXPECT_EQ(scene->camera.width, kW);
  EXPECT_EQ(scene->camera.height, kH);
  ASSERT_EQ(scene->surface.size(), static_cast<std::size_t>(kW * kH));
  // Linear depth 12 along the view axis: the centre pixels' rays are within a pixel of the axis,
  // a corner's is longer by 1/cos of its angle to the axis (about 1.27).
  EXPECT_NEAR(scene->surface[(kH / 2) * kW + kW / 2], 12.0, 0.05);
  EXPECT_GT(scene->surface[0], 12.0 * 1.2);
  EXPECT_DOUBLE_EQ(scene->medium.scattering, 0.06);
  EXPECT_EQ(ended, std::vector<std::string>{"reading " + request.depth_path + ": 16x12"});
}

TEST(AirlightRender, RefusesADensityForAHomogeneousMethodAndAProfileForANonSpotLight) {
  const test::TempDir dir;
  RenderRequest request = write_scene(dir);
  const std::string fog =
      dir.write("fog.json", R"({"scattering": 0.15, "absorption": 0.05, "intensity": 20,
          "density": {"type": "noise", "seed": 5, "frequency": 0.3, "octaves": 2}})");
  request.medium_path = fog;
  StageLog log;
  for (const RenderMethod ok :
       {RenderMethod::volume, RenderMethod::reference, RenderMethod::raymarch}) {
    request.method = ok;
    EXPECT_TRUE(load_render_scene(request, log)) << to_string(ok);
  }
  for (const RenderMethod refused : {RenderMethod::live, RenderMethod::radial}) {
    request.method = refused;
    Result<RenderScene> scene = load_render_scene(request, log);
    ASSERT_FALSE(scene);
    EXPECT_EQ(scene.error().message,
              fog + ": key 'density': RenderRequest::method " + to_string(refused) +
                  " renders homogeneous media only (volume, reference and raymarch take a "
                  "density)");
  }
  request = write_scene(dir);
  request.light_path = dir.write("sun.json", test::directional_json("linear"));
  request.medium_path =
      dir.write("profiled.json", R"({"scattering": 0.06, "absorption": 0.02, "intensity": 20,
          "profile": {"inner_deg": 10, "outer_deg": 20}})");
  Result<RenderScene> scene = load_render_scene(request, log);
  ASSERT_FALSE(scene);
  EXPECT_EQ(scene.error().message, request.medium_path +
                                       ": key 'profile': applies to spot lights only, " +
                                       request.light_path + " is a directional light");
}

TEST(AirlightRender, ReferenceIsRenderReferenceAsATimedStep) {
  const test::TempDir dir;
  const RenderRequest request = write_scene(dir);
  StageLog log;
  Result<RenderScene> scene = load_render_scene(request, log);
  ASSERT_TRUE(scene) << scene.error().message;
  Result<Mesh> volume =
      build_static_volume(scene->light, test::constant_depth(8, 8, 3.0f), {}, "8x8");
  ASSERT_TRUE(volume) << volume.error().message;
  const AirlightRender render = render_airlight_reference(*scene, *volume, log);
  EXPECT_EQ(render.image.values, render_reference(*volume, *scene).values);
  EXPECT_GT(image_levels(render.image).peak, 0);
  EXPECT_TRUE(render.frame_seconds.empty());
  EXPECT_EQ(render.renderer, "");
  EXPECT_EQ(log.stages().back().name, "rendering reference (CPU, double precision)");
}

TEST(AirlightRender, LevelsAndMedian) {
  Image image;
  image.width = 2;
  image.height = 2;
  image.values = {1.0, -3.0, 2.0, 4.0};
  const ImageLevels levels = image_levels(image);
  EXPECT_DOUBLE_EQ(levels.mean, 1.0);
  EXPECT_DOUBLE_EQ(levels.peak, 4.0);
  EXPECT_DOUBLE_EQ(image_levels(Image{}).mean, 0.0);
  EXPECT_DOUBLE_EQ(median({3, 1, 2}), 2.0);
  EXPECT_DOUBLE_EQ(median({4, 1, 3, 2}), 2.5);
  EXPECT_DOUBLE_EQ(median({}), 0.0);
}

TEST(AirlightRender, ComparesWithAnImageFileOfItsSizeOnly) {
  const test::TempDir dir;
  Image image;
  image.width = 3;
  image.height = 2;
  image.values = {0.5, 1, 2, 0.25, 0, 1};
  ASSERT_TRUE(write_image(dir.file("same.exr"), image));
  Result<ImageDifference> same = compare_with_image_file(image, dir.file("same.exr"));
  ASSERT_TRUE(same) << same.error().message;
  EXPECT_EQ(same->relative_l2, 0.0);
  EXPECT_EQ(same->max_abs, 0.0);
  Image wide = image;
  wide.width = 2;
  wide.height = 3;
  ASSERT_TRUE(write_image(dir.file("other.exr"), wide));
  Result<ImageDifference> other = compare_with_image_file(image, dir.file("other.exr"));
  ASSERT_FALSE(other);
  EXPECT_EQ(other.error().message, dir.file("other.exr") + ": image is 2x3, the render is 3x2");
  EXPECT_FALSE(compare_with_image_file(image, dir.file("missing.exr")));
}

}  // namespace
}  // namespace lightvol
