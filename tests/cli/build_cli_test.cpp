// `lightvol build` as a user runs it: exit codes, one-line errors, no partial or clobbered files.
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <lightvol/depth/depth_image.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

std::string q(const std::string& s) { return "'" + s + "'"; }

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

// A user's working directory: a 9×7 spot map with an occluder and its light.
struct Workspace {
  test::TempDir dir;
  std::string depth, light;
  Workspace() {
    depth = dir.file("depth.exr");
    const DepthImage d = test::make_depth(
        9, 7, [](int c, int r) { return (c > 2 && c < 6 && r > 1 && r < 5) ? 0.95f : 0.99f; });
    EXPECT_TRUE(write_depth_image(depth, d).ok());
    light = dir.write("light.json", test::spot_json());
  }
  test::CommandResult build(const std::string& extra) const {
    return test::run_lightvol("build " + q(depth) + " --light " + q(light) + " " + extra);
  }
};

// One line on stderr, "lightvol: ..." containing `needle`, exit 2.
void expect_input_error(const test::CommandResult& r, const std::string& needle) {
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err.rfind("lightvol: ", 0), 0u) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find(needle), std::string::npos) << r.err;
}

TEST(BuildCli, WritesTheVolumeAndAReport) {
  Workspace w;
  const std::string out = w.dir.file("v.ply"), report = w.dir.file("r.json");
  const test::CommandResult r = w.build("--out " + q(out) + " --report " + q(report));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("124 triangles"), std::string::npos) << r.out;  // 2·8·6 + 2·8 + 2·6
  const nlohmann::json j = nlohmann::json::parse(slurp(report));
  EXPECT_EQ(j["triangles"], 2 * 8 * 6 + 2 * 8 + 2 * 6);
  EXPECT_EQ(j["vertices"], 9 * 7 + 1);
  EXPECT_EQ(j["width"], 9);
  EXPECT_GT(j["volume"].get<double>(), 0);
  EXPECT_EQ(j["bounds"]["max"][1].get<double>(), 4.0);  // the apex is the highest point
  ASSERT_TRUE(j["stages"].is_array());
  EXPECT_GE(j["stages"].size(), 3u);
  for (const auto& s : j["stages"]) {
    EXPECT_GE(s["seconds"].get<double>(), 0);
    EXPECT_GT(s["peak_memory_bytes"].get<double>(), 0);
  }
}

TEST(BuildCli, QuietPrintsNothingAndJsonPrintsTheReport) {
  Workspace w;
  const test::CommandResult quiet = w.build("--out " + q(w.dir.file("v.obj")) + " --quiet");
  ASSERT_EQ(quiet.exit_code, 0) << quiet.err;
  EXPECT_EQ(quiet.out, "");
  EXPECT_EQ(quiet.err, "");
  const test::CommandResult json = w.build("--out " + q(w.dir.file("v.off")) + " --json");
  ASSERT_EQ(json.exit_code, 0) << json.err;
  EXPECT_EQ(nlohmann::json::parse(json.out)["triangles"], 124);
}

TEST(BuildCli, BadInputsExitTwoWithOneLineAndNoFile) {
  Workspace w;
  const std::string out = w.dir.file("v.ply");
  const int before = w.dir.entries();

  const std::string bad_light = w.dir.write("bad.json", R"({"type": "spot", "fov": 60})");
  expect_input_error(
      test::run_lightvol("build " + q(w.depth) + " --light " + q(bad_light) + " --out " + q(out)),
      "bad.json: key 'fov': unknown key");
  expect_input_error(test::run_lightvol("build " + q(w.dir.file("missing.exr")) + " --light " +
                                        q(w.light) + " --out " + q(out)),
                     "missing.exr: no such file");
  expect_input_error(w.build("--out " + q(w.dir.file("v.fbx"))), "unknown mesh format");
  expect_input_error(w.build("--out " + q(w.dir.file("no/such/dir/v.ply"))), "does not exist");
  expect_input_error(w.build("--out " + q(out) + " --draco"), "--draco");

  DepthImage nan = test::constant_depth(4, 4, 0.5f);
  nan.values[6] = std::numeric_limits<float>::quiet_NaN();
  const std::string nan_path = w.dir.file("nan.exr");
  ASSERT_TRUE(write_depth_image(nan_path, nan).ok());
  expect_input_error(
      test::run_lightvol("build " + q(nan_path) + " --light " + q(w.light) + " --out " + q(out)),
      "nan.exr: pixel (2, 1): depth is NaN");

  EXPECT_EQ(w.dir.entries(), before + 2);  // bad.json and nan.exr, nothing else
}

TEST(BuildCli, FailureNeverClobbersAnExistingOutput) {
  Workspace w;
  const std::string out = w.dir.write("v.drc", "an existing good file");
  const test::CommandResult r = w.build("--out " + q(out) + " --draco-bits 2");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("raise --draco-bits"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(out), "an existing good file");
}

// Draco's default 16 bits move the apex off the light; what build writes, check --light accepts,
// allowing for the step the file declares (and reporting it).
TEST(BuildCli, DracoVolumesPassCheckWithTheLight) {
  Workspace w;
  const std::string light = w.dir.write(
      "off_grid.json",
      R"({"type": "spot", "position": [0.37, 4.13, -0.21], "direction": [0, -1, 0], "up": [0, 0, -1],)"
      R"( "fov_y_deg": 60, "near": 0.1, "far": 30, "depth": "window"})");
  for (const std::string name : {"v.drc", "v.glb"}) {
    const std::string out = w.dir.file(name);
    const test::CommandResult r =
        test::run_lightvol("build " + q(w.depth) + " --light " + q(light) + " --quiet --out " +
                           q(out) + (name == "v.glb" ? " --draco" : ""));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const test::CommandResult check =
        test::run_lightvol("check " + q(out) + " --light " + q(light) + " --json");
    EXPECT_EQ(check.exit_code, 0) << check.out << check.err;
    const nlohmann::json j = nlohmann::json::parse(check.out);
    EXPECT_GT(j["quantization_step"].get<double>(), 0) << name;
    EXPECT_LT(j["quantization_step"].get<double>(), 1e-3) << name;
  }
}

TEST(BuildCli, UsageErrorsAndHelp) {
  EXPECT_EQ(test::run_lightvol("").exit_code, 2);
  EXPECT_EQ(test::run_lightvol("frobnicate").exit_code, 2);
  const test::CommandResult missing = test::run_lightvol("build depth.exr");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find("--light"), std::string::npos) << missing.err;
  const test::CommandResult help = test::run_lightvol("build --help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("--out"), std::string::npos);
  EXPECT_EQ(test::run_lightvol("--help").exit_code, 0);
}

TEST(BuildCli, GlbRecordsTheMediumGivenAndRefusesABadOne) {
  Workspace w;
  const std::string medium = w.dir.write(
      "medium.json", R"({"scattering": 0.2, "intensity": 30, "phase": {"type": "hg", "g": 0.5}})");
  const std::string out = w.dir.file("v.glb");
  const test::CommandResult ok = w.build("--out " + q(out) + " --medium " + q(medium) + " --quiet");
  ASSERT_EQ(ok.exit_code, 0) << ok.err;
  const std::string bytes = slurp(out);
  std::uint32_t length = 0;
  std::memcpy(&length, bytes.data() + 12, 4);
  const nlohmann::json doc = nlohmann::json::parse(bytes.substr(20, length));
  const nlohmann::json& node = doc["nodes"][doc["nodes"].size() - 1];
  EXPECT_EQ(node["extras"]["lightvol"]["medium"]["phase"]["g"], 0.5);
  EXPECT_EQ(doc["extensions"]["KHR_lights_punctual"]["lights"][0]["intensity"], 30.0);

  expect_input_error(w.build("--out " + q(w.dir.file("v.ply")) + " --medium " + q(medium)),
                     "--medium: applies to .glb output only");
  const std::string bad = w.dir.write("bad.json", R"({"scattering": -1})");
  expect_input_error(w.build("--out " + q(w.dir.file("w.glb")) + " --medium " + q(bad)),
                     "bad.json");
  EXPECT_FALSE(std::filesystem::exists(w.dir.file("w.glb")));
  EXPECT_FALSE(std::filesystem::exists(w.dir.file("v.ply")));
}

}  // namespace
}  // namespace lightvol
