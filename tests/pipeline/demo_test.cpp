// pipeline/demo.h: run_demo on the bundled data at a small size without OpenGL (CPU depth passes,
// no pictures), with GPU steps that stand in for lightvol::gl's (what they are given, and when
// they are skipped), and what it refuses.
#include <algorithm>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/io/mesh_reader.h>
#include <lightvol/pipeline/demo.h>

#include "support/test_support.h"

namespace lightvol {
namespace {
namespace fs = std::filesystem;

const std::string kData = std::string(LIGHTVOL_SOURCE_DIR) + "/data";

std::vector<std::string> steps(const DemoReport& report) {
  std::vector<std::string> names;
  for (const DemoRow& row : report.rows) names.push_back(row.step);
  return names;
}

DemoOptions small(const test::TempDir& dir) {
  DemoOptions o;
  o.data_dir = kData;
  o.out_dir = dir.file("out");
  o.size = 16;
  return o;
}

TEST(Demo, WithoutOpenGlWritesTheMapsVolumesAndViewerInputsAndSkipsThePictures) {
  const test::TempDir dir;
  const DemoOptions o = small(dir);
  StageLog log;
  Result<DemoReport> report = run_demo(o, log);
  ASSERT_TRUE(report) << report.error().message;
  // The camera image shrinks with the map (480x360 × 16/512), to no less than 16 pixels a side.
  EXPECT_EQ(steps(*report),
            (std::vector<std::string>{"shadow map 16x16", "camera depth 16x16", "static volume",
                                      "adaptive volume", "web viewer inputs", "check static",
                                      "check adaptive", "render"}));
  const std::vector<DemoRow>& rows = report->rows;
  EXPECT_EQ(rows[0].size, "27,336 scene");
  EXPECT_EQ(rows[0].result, "CPU ray casting (built without OpenGL (LIGHTVOL_WITH_GL=OFF))");
  EXPECT_EQ(rows[2].size, "510 tris");  // 2·16² − 2: the grid and the spot's fan
  EXPECT_EQ(rows[3].result, "max error 0.01");
  EXPECT_EQ(rows[5].result.rfind("valid (", 0), 0u) << rows[5].result;
  EXPECT_EQ(rows[7].result, "skipped: built without OpenGL");
  for (const char* file :
       {"shadow_map.exr", "shadow_map.png", "camera_depth.exr", "camera_depth.png",
        "volume_static.ply", "volume_adaptive.ply", "volume_static.glb", "volume_adaptive.glb",
        "scene.glb", "camera.json", "light.json", "medium.json"})
    EXPECT_TRUE(fs::is_regular_file(o.out_dir + "/" + file)) << file;
  Result<Mesh> fixed = read_mesh(o.out_dir + "/volume_static.ply");
  ASSERT_TRUE(fixed) << fixed.error().message;
  EXPECT_EQ(fixed->num_triangles(), 510u);
  EXPECT_TRUE(test::is_closed_and_oriented(*fixed));
  // The table: a header and a line per row, the seconds of each step beside its result.
  const std::string table = demo_table(*report);
  EXPECT_EQ(table.rfind("step                       output                 size", 0), 0u) << table;
  EXPECT_NE(table.find("\nstatic volume              volume_static.ply      510 tris          "),
            std::string::npos)
      << table;
  EXPECT_EQ(std::count(table.begin(), table.end(), '\n'), 9);
}

TEST(Demo, GpuStepsGetTheVolumesAndMapsOrAreSkippedWhenTheirDepthPassesCannotRun) {
  const test::TempDir dir;
  DemoOptions o = small(dir);
  std::vector<std::string> seen;
  o.gpu.depth_passes = [](const Mesh& scene, const std::string&) {
    return Result<std::unique_ptr<DepthPasses>>(cpu_depth_passes(scene));
  };
  o.gpu.pictures = [&](const DemoPictureInputs& in, StageLog& log, std::vector<DemoRow>* rows) {
    for (const DemoVolume& v : in.volumes)
      seen.push_back(v.name + " " + std::to_string(v.mesh.num_triangles()));
    seen.push_back("map " + std::to_string(in.shadow.width()) + " " +
                   std::to_string(in.shadow_window.size()));
    seen.push_back("surface " + std::to_string(in.scene.surface.size()));
    seen.push_back(in.out_dir);
    log.begin("pictures");
    log.end();
    rows->push_back({"pictures", "demo.png", "", "", log.last_seconds()});
    return Status();
  };
  StageLog log;
  Result<DemoReport> report = run_demo(o, log);
  ASSERT_TRUE(report) << report.error().message;
  ASSERT_EQ(seen.size(), 5u);
  EXPECT_EQ(seen[0], "static 510");
  EXPECT_EQ(seen[1].rfind("adaptive ", 0), 0u);
  EXPECT_EQ(seen[2], "map 16 256");
  EXPECT_EQ(seen[3], "surface 256");
  EXPECT_EQ(seen[4], o.out_dir);
  EXPECT_EQ(report->rows[0].result, "CPU ray casting");
  EXPECT_EQ(report->rows.back().step, "pictures");

  // Depth passes that cannot run: the CPU's run instead, and the pictures are skipped.
  o.gpu.depth_passes = [](const Mesh&, const std::string& source) {
    return Result<std::unique_ptr<DepthPasses>>(Error{source + ": no display"});
  };
  seen.clear();
  report = run_demo(o, log);
  ASSERT_TRUE(report) << report.error().message;
  EXPECT_TRUE(seen.empty());
  const std::string why = kData + "/sponza_crop.ply: no display";
  EXPECT_EQ(report->rows[0].result, "CPU ray casting (" + why + ")");
  EXPECT_EQ(report->rows.back().step, "render");
  EXPECT_EQ(report->rows.back().result, "skipped: no OpenGL (" + why + ")");
}

TEST(Demo, RefusesAFolderWithoutTheSceneAndAnOutputThatIsNoFolder) {
  const test::TempDir dir;
  DemoOptions o = small(dir);
  o.data_dir = dir.path();
  StageLog log;
  Result<DemoReport> report = run_demo(o, log);
  ASSERT_FALSE(report);
  EXPECT_EQ(report.error().message.rfind(dir.file("sponza_crop.ply") + ": ", 0), 0u)
      << report.error().message;
  EXPECT_NE(report.error().message.find(" (is DemoOptions::data_dir the bundled data/ folder?)"),
            std::string::npos)
      << report.error().message;
  o = small(dir);
  o.out_dir = dir.write("file", "x");
  report = run_demo(o, log);
  ASSERT_FALSE(report);
  EXPECT_EQ(report.error().message, o.out_dir + ": cannot create the output directory");
}

}  // namespace
}  // namespace lightvol
