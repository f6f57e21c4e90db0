// pipeline/: build_volume_file (what `lightvol build` calls) from a light and maps in memory, its
// report and stage log, what it refuses; the files a build reads (depth_input_files,
// build_input_files).
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <thread>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <lightvol/depth/cube_faces.h>
#include <lightvol/io/mesh_reader.h>
#include <lightvol/pipeline/build_file.h>
#include <lightvol/pipeline/build_job.h>
#include <lightvol/pipeline/detail/build_hooks.h>

#include "support/test_support.h"

namespace lightvol {
namespace {
using namespace test;

// A 3×3 spot map at linear depth 2: the static volume has 9 texel vertices and the apex, 8 grid
// triangles and 8 in the fan.
struct SmallSpot {
  Light light = light_from_json(spot_json("linear"));
  ShadowMaps maps = ShadowMaps::planar(constant_depth(3, 3, 2.0f), "3x3");
};

TEST(BuildFile, InMemoryLightAndMapsGiveTheCheckedVolumeItsFileAndItsReport) {
  const SmallSpot spot;
  const TempDir dir;
  BuildFileOptions o;
  o.light = &spot.light;
  o.maps = &spot.maps;
  o.light_path = "spot.json";
  o.out_path = dir.file("volume.ply");
  o.report_path = dir.file("volume.report.json");
  o.keep_mesh = true;
  std::vector<std::string> begun, ended;
  StageLog log;
  log.on_begin = [&](const std::string& name) { begun.push_back(name); };
  log.on_end = [&](const StageRecord& s, const std::string& detail) {
    ended.push_back(s.name + (detail.empty() ? "" : ": " + detail));
  };
  const BuildFileResult r = build_volume_file(o, log);
  ASSERT_TRUE(r.status.ok()) << r.status.error().message;
  EXPECT_EQ(r.triangles, 16u);
  EXPECT_EQ(r.vertices, 10u);
  EXPECT_TRUE(r.check.valid());
  EXPECT_EQ(r.mesh.num_triangles(), 16u);
  EXPECT_DOUBLE_EQ(r.volume, signed_volume(r.mesh));
  // Nothing was read: the steps are the build, the check and the write, each begun and ended.
  const std::vector<std::string> steps = {"building static volume", "checking",
                                          "writing " + o.out_path};
  EXPECT_EQ(begun, steps);
  EXPECT_EQ(ended, (std::vector<std::string>{"building static volume: 16 triangles",
                                             "checking: valid", "writing " + o.out_path}));
  ASSERT_EQ(log.stages().size(), 3u);
  // The file holds the volume; the report file is the report's text and a line break.
  const Result<Mesh> back = read_mesh(o.out_path);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(back->num_triangles(), 16u);
  EXPECT_EQ(slurp(o.report_path), r.report + "\n");
  const nlohmann::json report = nlohmann::json::parse(r.report);
  EXPECT_EQ(report["triangles"], 16);
  EXPECT_EQ(report["vertices"], 10);
  EXPECT_EQ(report["mode"], "static");
  EXPECT_EQ(report["space"], "world");
  EXPECT_EQ(report["output"], o.out_path);
  EXPECT_EQ(report["light"]["path"], "spot.json");
  EXPECT_EQ(report["light"]["type"], "spot");
  EXPECT_EQ(report["width"], 3);
  EXPECT_EQ(report["stages"].size(), 3u);
  EXPECT_EQ(report["volume"].get<double>(), r.volume);
}

TEST(BuildFile, AdaptiveReportsItsBoundAndTessellation) {
  const Light light = light_from_json(spot_json("linear"));
  const ShadowMaps maps = ShadowMaps::planar(constant_depth(17, 17, 2.0f), "17x17");
  const TempDir dir;
  BuildFileOptions o;
  o.light = &light;
  o.maps = &maps;
  o.out_path = dir.file("volume.off");
  o.make_report = true;
  o.volume.grid = VolumeGrid::adaptive;
  o.volume.adaptive.max_error = 0.01;
  StageLog log;
  const BuildFileResult r = build_volume_file(o, log);
  ASSERT_TRUE(r.status.ok()) << r.status.error().message;
  EXPECT_TRUE(r.mesh.indices.empty());  // not kept unless asked
  const nlohmann::json report = nlohmann::json::parse(r.report);
  EXPECT_EQ(report["mode"], "adaptive");
  EXPECT_EQ(report["adaptive"]["refine"], "error");
  EXPECT_EQ(report["adaptive"]["tessellation"], "collapse");
  EXPECT_EQ(report["adaptive"]["max_error"], 0.01);
  EXPECT_TRUE(report["adaptive"]["threshold"].is_null());
  // A flat map: far fewer triangles than the static grid's 512 (and its fan's 64), and the bound
  // holds.
  EXPECT_LT(r.triangles, 512u);
  EXPECT_LE(report["adaptive"]["max_error_reached"].get<double>(), 0.01);
}

// Whether a temporary of core/atomic_file.h (".lv-" and 16 characters) is in `dir`, or appears in
// it within 10 s: the volume's file being written (staged) while the check runs.
bool temporary_in(const std::string& dir) {
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().filename().string().rfind(".lv-", 0) == 0) return true;
  return false;
}
bool temporary_appears(const std::string& dir) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!temporary_in(dir)) {
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

// A build whose volume is broken before its check (one face turned over: "oriented" fails). The
// streaming writers (PLY, OBJ, OFF, STL) write the volume's file while the check runs, so its
// temporary is there during the "checking" stage; the failure then removes it with the report's,
// and nothing is written, exactly as when the check ran first (a GLB still waits for the check).
TEST(BuildFile, AVolumeThatFailsItsCheckWhileItIsWrittenLeavesNoFileAndNoTemporary) {
  const SmallSpot spot;
  for (const bool adaptive : {false, true})
    for (const char* ext : {"ply", "obj", "off", "stl", "glb"}) {
      SCOPED_TRACE(std::string(ext) + (adaptive ? " adaptive" : " static"));
      const TempDir dir;
      BuildFileOptions o;
      o.light = &spot.light;
      o.maps = &spot.maps;
      o.out_path = dir.file(std::string("volume.") + ext);
      o.report_path = dir.file("volume.report.json");
      if (adaptive) {
        o.volume.grid = VolumeGrid::adaptive;
        o.volume.adaptive.max_error = 0.01;
      }
      detail::BuildFileHooks hooks;
      hooks.before_check = [](Mesh& volume) { std::swap(volume.indices[1], volume.indices[2]); };
      StageLog log;
      std::vector<std::string> begun;
      bool staged_while_checking = false;
      log.on_begin = [&](const std::string& name) {
        begun.push_back(name);
        if (name == "checking")
          staged_while_checking =
              std::string(ext) == "glb" ? temporary_in(dir.path()) : temporary_appears(dir.path());
      };
      const BuildFileResult r = detail::build_volume_file(o, log, hooks);
      ASSERT_FALSE(r.status.ok());
      EXPECT_EQ(r.status.error().kind, ErrorKind::unsound);
      EXPECT_EQ(
          r.status.error().message.rfind(
              o.out_path + ": the built volume fails its checks, nothing written: oriented", 0),
          0u)
          << r.status.error().message;
      EXPECT_FALSE(r.check.valid());
      EXPECT_EQ(staged_while_checking, std::string(ext) != "glb");
      EXPECT_EQ(dir.entries(), 0);  // no volume, no report, no temporary
      ASSERT_EQ(begun.size(), 2u);
      EXPECT_EQ(begun[1], "checking");  // and no "writing" stage
      EXPECT_EQ(log.stages().size(), 1u);
    }
}

// A stream output (here a pipe named by its descriptor) is spooled in TMPDIR while the check runs
// and written through only once the check has passed: a failing check writes nothing to it.
TEST(BuildFile, AStreamOutputGetsNothingFromAVolumeThatFailsItsCheck) {
  const SmallSpot spot;
  const TempDir spool, links;
  const char* old_tmpdir = std::getenv("TMPDIR");
  const std::string saved = old_tmpdir ? old_tmpdir : "";
  ::setenv("TMPDIR", spool.path().c_str(), 1);
  for (const bool broken : {true, false}) {
    SCOPED_TRACE(broken ? "failing check" : "passing check");
    int fds[2];
    ASSERT_EQ(::pipe(fds), 0);
    // The format comes from the extension: a symlink named *.ply leads to the pipe's descriptor.
    std::filesystem::remove(links.file("out.ply"));
    std::filesystem::create_symlink("/dev/fd/" + std::to_string(fds[1]), links.file("out.ply"));
    BuildFileOptions o;
    o.light = &spot.light;
    o.maps = &spot.maps;
    o.out_path = links.file("out.ply");
    detail::BuildFileHooks hooks;
    if (broken)
      hooks.before_check = [](Mesh& volume) { std::swap(volume.indices[1], volume.indices[2]); };
    StageLog log;
    bool spooled_while_checking = false;
    log.on_begin = [&](const std::string& name) {
      if (name == "checking") spooled_while_checking = temporary_appears(spool.path());
    };
    const BuildFileResult r = detail::build_volume_file(o, log, hooks);
    ::close(fds[1]);
    std::string received;
    char buffer[4096];
    for (ssize_t n; (n = ::read(fds[0], buffer, sizeof buffer)) > 0;)
      received.append(buffer, static_cast<std::size_t>(n));
    ::close(fds[0]);
    EXPECT_TRUE(spooled_while_checking);
    EXPECT_EQ(spool.entries(), 0);                         // the spool is gone either way
    EXPECT_TRUE(std::filesystem::is_symlink(o.out_path));  // written through, never replaced
    if (broken) {
      ASSERT_FALSE(r.status.ok());
      EXPECT_EQ(r.status.error().kind, ErrorKind::unsound);
      EXPECT_TRUE(received.empty()) << received.size() << " bytes";
    } else {
      ASSERT_TRUE(r.status.ok()) << r.status.error().message;
      EXPECT_EQ(received.rfind("ply\n", 0), 0u);
    }
  }
  if (old_tmpdir)
    ::setenv("TMPDIR", saved.c_str(), 1);
  else
    ::unsetenv("TMPDIR");
}

// The streaming writers write a checked volume while it is checked (its temporary is there during
// "checking"); the bytes are those of the same volume written unchecked, after its build.
TEST(BuildFile, AVolumeWrittenWhileItIsCheckedHasTheBytesOfOneWrittenUnchecked) {
  const SmallSpot spot;
  for (const bool adaptive : {false, true})
    for (const char* ext : {"ply", "obj", "off", "stl"}) {
      SCOPED_TRACE(std::string(ext) + (adaptive ? " adaptive" : " static"));
      const TempDir dir;
      BuildFileOptions o;
      o.light = &spot.light;
      o.maps = &spot.maps;
      if (adaptive) {
        o.volume.grid = VolumeGrid::adaptive;
        o.volume.adaptive.max_error = 0.01;
      }
      o.out_path = dir.file(std::string("unchecked.") + ext);
      o.check = false;
      o.make_report = true;
      StageLog unchecked_log;
      const BuildFileResult unchecked = build_volume_file(o, unchecked_log);
      ASSERT_TRUE(unchecked.status.ok()) << unchecked.status.error().message;
      o.out_path = dir.file(std::string("checked.") + ext);
      o.report_path = dir.file("checked.report.json");
      o.check = true;
      o.keep_mesh = true;
      StageLog log;
      std::vector<std::string> begun;
      bool staged_while_checking = false;
      log.on_begin = [&](const std::string& name) {
        begun.push_back(name);
        if (name == "checking") staged_while_checking = temporary_appears(dir.path());
      };
      const BuildFileResult r = build_volume_file(o, log);
      ASSERT_TRUE(r.status.ok()) << r.status.error().message;
      EXPECT_TRUE(staged_while_checking);
      EXPECT_TRUE(r.check.valid());
      EXPECT_EQ(slurp(o.out_path), slurp(dir.file(std::string("unchecked.") + ext)));
      // The report's bounds and volume, taken from the check's report, are bounding_box's and
      // signed_volume's (which the unchecked build measures) to the bit.
      EXPECT_EQ(r.volume, unchecked.volume);
      EXPECT_EQ(nlohmann::json::parse(r.report)["bounds"],
                nlohmann::json::parse(unchecked.report)["bounds"]);
      EXPECT_EQ(r.volume, signed_volume(r.mesh));
      EXPECT_EQ(dir.entries(), 3);  // the two volumes and the report: no temporary left
      EXPECT_EQ(begun.back(), "writing " + o.out_path);
      ASSERT_EQ(log.stages().size(), 3u);
      EXPECT_EQ(log.stages()[1].name, "checking");
      // The report records the stages as they were logged: the write's stage is what of the write
      // was left when the check ended.
      const nlohmann::json report = nlohmann::json::parse(slurp(o.report_path));
      ASSERT_EQ(report["stages"].size(), 3u);
      EXPECT_EQ(report["stages"][1]["name"], "checking");
      EXPECT_EQ(report["stages"][2]["name"], "writing " + o.out_path);
    }
}

TEST(BuildFile, AnOutputThatIsAnInputIsRefusedNamingBothOptionsAndWritesNothing) {
  const TempDir dir;
  const std::string light = dir.write("light.json", spot_json("linear"));
  BuildFileOptions o;
  o.light_path = light;
  o.depth_paths = {dir.file("depth.exr")};
  o.out_path = dir.file("volume.ply");
  o.report_path = light;
  StageLog log;
  const BuildFileResult r = build_volume_file(o, log);
  ASSERT_FALSE(r.status.ok());
  EXPECT_EQ(r.status.error().message, "BuildFileOptions::report_path " + light +
                                          ": is also the BuildFileOptions::light_path " + light +
                                          "; an output may not replace an input");
  EXPECT_EQ(slurp(light), spot_json("linear"));
  EXPECT_EQ(dir.entries(), 1);
  EXPECT_TRUE(log.stages().empty());  // refused before anything is read
}

TEST(BuildFile, ControlCharactersAndUnknownFormatsAreRefusedBeforeReading) {
  const SmallSpot spot;
  const TempDir dir;
  BuildFileOptions o;
  o.light = &spot.light;
  o.maps = &spot.maps;
  o.out_path = dir.file("volume\n.ply");
  StageLog log;
  BuildFileResult r = build_volume_file(o, log);
  ASSERT_FALSE(r.status.ok());
  EXPECT_EQ(
      r.status.error().message.rfind("BuildFileOptions::out_path: control character \\x0a", 0), 0u)
      << r.status.error().message;
  o.out_path = dir.file("volume.xyz");
  r = build_volume_file(o, log);
  ASSERT_FALSE(r.status.ok());
  EXPECT_NE(r.status.error().message.find("volume.xyz"), std::string::npos);
  EXPECT_EQ(dir.entries(), 0);
  EXPECT_TRUE(log.stages().empty());
}

TEST(BuildInputs, FacePathsAreSixFilesAndEveryInputIsListedWithItsKey) {
  EXPECT_EQ(depth_input_files({"a.exr"}), std::vector<std::string>{"a.exr"});
  EXPECT_EQ(depth_input_files({"room_{face}.exr"}),
            (std::vector<std::string>{"room_px.exr", "room_nx.exr", "room_py.exr", "room_ny.exr",
                                      "room_pz.exr", "room_nz.exr"}));
  BuildFileOptions o;
  o.depth_paths = {"c_{face}.pfm"};
  o.light_path = "omni.json";
  o.medium_path = "fog.json";
  const auto files = build_input_files(o);
  ASSERT_EQ(files.size(), 8u);
  EXPECT_EQ(files[0], (std::pair<std::string, std::string>{"inputs", "c_px.pfm"}));
  EXPECT_EQ(files[5], (std::pair<std::string, std::string>{"inputs", "c_nz.pfm"}));
  EXPECT_EQ(files[6], (std::pair<std::string, std::string>{"light", "omni.json"}));
  EXPECT_EQ(files[7], (std::pair<std::string, std::string>{"args: --medium", "fog.json"}));
}

}  // namespace
}  // namespace lightvol
