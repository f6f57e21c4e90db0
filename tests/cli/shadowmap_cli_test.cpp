// `lightvol shadowmap` from the command line: sizes, omni faces and strips, camera depth, errors.
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include <lightvol/depth/depth_image.h>

#include "support/gl_test_context.h"
#include "support/test_support.h"

namespace lightvol {
namespace {

// A unit box on a floor, as OBJ.
const char* kSceneObj =
    "v -10 0 -10\nv 10 0 -10\nv 10 0 10\nv -10 0 10\n"
    "v -1 0 -1\nv 1 0 -1\nv 1 2 -1\nv -1 2 -1\nv -1 0 1\nv 1 0 1\nv 1 2 1\nv -1 2 1\n"
    "f 1 3 2\nf 1 4 3\n"
    "f 5 7 6\nf 5 8 7\nf 9 10 11\nf 9 11 12\nf 5 9 12\nf 5 12 8\nf 6 7 11\nf 6 11 10\n"
    "f 8 12 11\nf 8 11 7\n";

class ShadowmapCli : public ::testing::Test {
 protected:
  void SetUp() override {
    scene_ = dir_.write("scene.obj", kSceneObj);
    spot_ =
        dir_.write("spot.json", R"({"type": "spot", "position": [0, 6, 0], "direction": [0, -1, 0],
        "up": [0, 0, -1], "fov_y_deg": 60, "aspect": 2, "near": 0.5, "far": 20})");
    omni_ = dir_.write("omni.json",
                       R"({"type": "omni", "position": [0, 4, 0], "near": 0.1, "far": 30})");
  }
  test::TempDir dir_;
  std::string scene_, spot_, omni_;
};

TEST_F(ShadowmapCli, SpotMapIsNWideAndNOverAspectHigh) {
  REQUIRE_GL_CONTEXT();
  const std::string out = dir_.file("d.exr");
  const test::CommandResult r =
      test::run_lightvol("shadowmap " + scene_ + " --light " + spot_ + " --size 64 --out " + out +
                         " --preview " + dir_.file("p.png"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  Result<DepthImage> d = read_depth_image(out);
  ASSERT_TRUE(d) << d.error().message;
  EXPECT_EQ(d->width, 64);
  EXPECT_EQ(d->height, 32);
  // The box top (eye depth 4) is nearer than the floor (6) at the centre; the corners see floor.
  EXPECT_LT(d->at(32, 16), d->at(0, 0));
  EXPECT_LT(d->at(0, 0), 1.0f);
  EXPECT_TRUE(std::filesystem::exists(dir_.file("p.png")));
}

TEST_F(ShadowmapCli, OmniFacesAsFilesOrAStrip) {
  REQUIRE_GL_CONTEXT();
  test::CommandResult r = test::run_lightvol("shadowmap " + scene_ + " --light " + omni_ +
                                             " --size 16 --out " + dir_.file("c_{face}.exr"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* tag : {"px", "nx", "py", "ny", "pz", "nz"}) {
    Result<DepthImage> d = read_depth_image(dir_.file(std::string("c_") + tag + ".exr"));
    ASSERT_TRUE(d) << tag;
    EXPECT_EQ(d->width, 16);
    EXPECT_EQ(d->height, 16);
  }
  r = test::run_lightvol("shadowmap " + scene_ + " --light " + omni_ + " --size 16 --out " +
                         dir_.file("strip.exr"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  Result<DepthImage> strip = read_depth_image(dir_.file("strip.exr"));
  ASSERT_TRUE(strip);
  EXPECT_EQ(strip->width, 16);
  EXPECT_EQ(strip->height, 96);
  // Face −Y (rows 48..63) looks down at the box top: hit everywhere; +Y (rows 32..47) sees nothing.
  Result<DepthImage> ny = read_depth_image(dir_.file("c_ny.exr"));
  ASSERT_TRUE(ny);
  for (int row = 0; row < 16; ++row)
    for (int col = 0; col < 16; ++col) {
      EXPECT_EQ(strip->at(col, 48 + row), ny->at(col, row));
      EXPECT_LT(strip->at(col, 48 + row), 1.0f);
      EXPECT_EQ(strip->at(col, 32 + row), 1.0f);
    }
}

TEST_F(ShadowmapCli, CameraDepthTakesTheCameraSize) {
  REQUIRE_GL_CONTEXT();
  const std::string camera =
      dir_.write("camera.json", R"({"position": [0, 3, 8], "direction": [0, -0.3, -1],
      "up": [0, 1, 0], "fov_y_deg": 50, "aspect": 1.5, "near": 0.1, "far": 40, "depth": "linear",
      "width": 48, "height": 32})");
  const test::CommandResult r = test::run_lightvol("shadowmap " + scene_ + " --camera " + camera +
                                                   " --out " + dir_.file("cam.exr"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  Result<DepthImage> d = read_depth_image(dir_.file("cam.exr"));
  ASSERT_TRUE(d);
  EXPECT_EQ(d->width, 48);
  EXPECT_EQ(d->height, 32);
  EXPECT_GT(d->at(24, 16), 5.0f);  // linear depth of the box front, about 7 units away
  EXPECT_LT(d->at(24, 16), 9.0f);
}

TEST_F(ShadowmapCli, BadUsageExitsTwoWithTheReasonAndWritesNothing) {
  const std::string out = dir_.file("never.exr");
  struct Case {
    std::string args, message;
  } cases[] = {
      {"shadowmap " + scene_ + " --light " + spot_ + " --out " + out, "--size: required"},
      {"shadowmap " + scene_ + " --light " + spot_ + " --camera " + spot_ + " --size 8 --out " +
           out,
       "exactly one of --light"},
      {"shadowmap " + scene_ + " --light " + spot_ + " --size 1 --out " + out, "--size: must lie"},
      {"shadowmap " + scene_ + " --light " + spot_ + " --size 8 --out " + dir_.file("x_{face}.exr"),
       "{face} applies to omni lights only"},
      {"shadowmap " + dir_.file("missing.obj") + " --light " + spot_ + " --size 8 --out " + out,
       "missing.obj"},
  };
  for (const Case& c : cases) {
    const test::CommandResult r = test::run_lightvol(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_FALSE(std::filesystem::exists(out));
  }
}

}  // namespace
}  // namespace lightvol
