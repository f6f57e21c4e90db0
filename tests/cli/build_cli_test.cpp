// `lightvol build` as a user runs it: exit codes, one-line errors, no partial or clobbered files.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <thread>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <lightvol/depth/depth_image.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

using test::q;
using test::slurp;

// A user's working directory: a 9×7 spot map with an occluder and its light.
struct Workspace {
  test::TempDir dir;
  std::string depth, light;
  Workspace() {
    depth = dir.file("depth.exr");
    const DepthImage d = test::make_depth(
        9, 7, [](int c, int r) { return (c > 2 && c < 6 && r > 1 && r < 5) ? 0.95f : 0.99f; });
    EXPECT_TRUE(write_depth_image(depth, d).ok());
    light = dir.write("light.json", test::spot_json("window", 9.0 / 7.0));  // square texels
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

// Before: the volume was renamed into place before the report was tried, so a failing report
// (a directory, a missing folder) left the new volume over the old one; --report equal to --out
// left JSON in the .ply.
TEST(BuildCli, AFailingReportLeavesTheOldVolume) {
  Workspace w;
  const std::string out = w.dir.write("keep.ply", "OLD\n");
  std::filesystem::create_directory(w.dir.file("rdir"));
  const int before = w.dir.entries();
  expect_input_error(w.build("--out " + q(out) + " --report " + q(w.dir.file("rdir"))),
                     "is a directory");
  expect_input_error(w.build("--out " + q(out) + " --report " + q(w.dir.file("nope/r.json"))),
                     "does not exist");
  expect_input_error(w.build("--out " + q(out) + " --report " + q(out)),
                     "another output of this run");
  EXPECT_EQ(slurp(out), "OLD\n");
  EXPECT_EQ(w.dir.entries(), before);  // no temporary left either
}

// Before: with stdout redirected to a file (as run_lightvol does), /dev/stdout led to a regular
// file, so the temporary was made in /dev and renamed over the /dev/stdout symlink: the machine
// lost /dev/stdout and the file got nothing. (Not run on that code: it harms the machine;
// AtomicFile.DescriptorPathsAreWrittenThroughAtTheirOffset shows the same with a link of its own.)
TEST(BuildCli, ReportOnStandardOutput) {
  Workspace w;
  for (const std::string report : {"/dev/stdout", "-"}) {
    const std::string out = w.dir.file("v.ply");
    const test::CommandResult r = w.build("--out " + q(out) + " --report " + report);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json j = nlohmann::json::parse(r.out);  // only the report: the summary is
    EXPECT_EQ(j["triangles"], 124);                         // on stderr
    EXPECT_NE(r.err.find("wrote " + out + ": 124 triangles"), std::string::npos) << r.err;
    EXPECT_TRUE(std::filesystem::is_symlink("/dev/stdout"));
    EXPECT_TRUE(std::filesystem::is_regular_file(out));
  }
  expect_input_error(w.build("--out " + q(w.dir.file("v.ply")) + " --report - --json"),
                     "--report -: --json prints the report on standard output already");
  EXPECT_EQ(std::count_if(
                std::filesystem::directory_iterator("/dev"), {},
                [](const auto& e) { return e.path().filename().string().rfind(".lv-", 0) == 0; }),
            0);
}

bool has_temporaries(const std::string& dir) {
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().filename().string().rfind(".lv-", 0) == 0) return true;
  return false;
}

// Before: the JSON library threw on the Latin-1 bytes of the names and the process aborted (exit
// 134): --report left .lv-* temporaries, --json committed the volume first. A byte that is not
// UTF-8 now reaches the JSON as U+FFFD.
TEST(BuildCli, Latin1NamesReachReportsAsReplacementCharacters) {
  Workspace w;
  const std::string folder = w.dir.file("caf\xe9");
  ASSERT_TRUE(std::filesystem::create_directory(folder));
  const std::string depth = folder + "/d\xe9pth.exr", light = folder + "/l.json";
  std::filesystem::copy_file(w.depth, depth);
  std::filesystem::copy_file(w.light, light);
  const std::string out = folder + "/v.ply", report = folder + "/r.json";
  const std::string shown = w.dir.path() + "/caf\xef\xbf\xbd/d\xef\xbf\xbdpth.exr";

  test::CommandResult r = test::run_lightvol("build " + q(depth) + " --light " + q(light) +
                                             " --out " + q(out) + " --report " + q(report));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(slurp(report))["inputs"][0], shown);
  EXPECT_FALSE(has_temporaries(folder));

  r = test::run_lightvol("build " + q(depth) + " --light " + q(light) + " --out " + q(out) +
                         " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["inputs"][0], shown);

  r = test::run_lightvol("check " + q(out) + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["mesh"], w.dir.path() + "/caf\xef\xbf\xbd/v.ply");
  EXPECT_FALSE(has_temporaries(folder));
}

// Before: the quoted value was cut at 81 bytes, inside a two-byte character, and the JSON library
// threw on it: exit 134. Quotes are cut on character boundaries.
TEST(BuildCli, LongNonAsciiValuesAreQuotedWholeCharacters) {
  Workspace w;
  std::string e60;
  for (int i = 0; i < 60; ++i) e60 += "\xc3\xa9";  // é
  const std::string light = w.dir.write(
      "l.json", R"({"type": ")" + e60 + R"(", "position": [0, 4, 0], "direction": [0, -1, 0]})");
  std::string e37;
  for (int i = 0; i < 37; ++i) e37 += "\xc3\xa9";
  expect_input_error(
      test::run_lightvol("build " + q(w.depth) + " --light " + q(light) + " --out " +
                         q(w.dir.file("v.ply"))),
      "key 'type': expected \"spot\", \"directional\" or \"omni\", got \"" + e37 + "...\"");
}

// Before: a line break in a path was taken as it is (a file "v\n.ply", messages split in two).
TEST(BuildCli, ControlCharactersInPathsAreRefused) {
  Workspace w;
  const int before = w.dir.entries();
  expect_input_error(w.build("--out " + q(w.dir.file("v\n.ply"))),
                     "--out: control character \\x0a at byte " +
                         std::to_string(w.dir.path().size() + 2) +
                         " in the path; paths may not hold one");
  expect_input_error(
      w.build("--out " + q(w.dir.file("v.ply")) + " --report " + q(w.dir.file("r\t.json"))),
      "--report: control character \\x09");
  EXPECT_EQ(w.dir.entries(), before);
}

// Before: --report over the light (or the depth map) replaced the input with the report.
TEST(BuildCli, NoOutputReplacesAnInput) {
  Workspace w;
  const std::string light_text = slurp(w.light);
  const std::string link = w.dir.file("also_light.json");
  ASSERT_EQ(::symlink(w.light.c_str(), link.c_str()), 0);
  const int before = w.dir.entries();
  expect_input_error(w.build("--out " + q(w.dir.file("v.ply")) + " --report " + q(link)),
                     "--report " + link + ": is also the --light " + w.light +
                         "; an output may not replace an input");
  expect_input_error(w.build("--out " + q(w.dir.file("v.ply")) + " --report " + q(w.depth)),
                     "--report " + w.depth + ": is also the depth input " + w.depth);
  EXPECT_EQ(slurp(w.light), light_text);
  EXPECT_EQ(w.dir.entries(), before);
}

// Before: SIGINT, SIGTERM or SIGHUP during the write left the partial temporary beside the output.
TEST(BuildCli, InterruptedWriteLeavesNothing) {
  Workspace w;
  const std::string big = w.dir.file("big.exr");
  ASSERT_TRUE(write_depth_image(
                  big, test::make_depth(
                           1200, 1200,
                           [](int c, int r) {
                             return 0.9f + 0.05f * static_cast<float>((c * 7 + r * 3) % 17) / 17;
                           }))
                  .ok());
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
    const int before = w.dir.entries();
    const std::string out = w.dir.file("big.ply");
    // On a loaded machine the test can be descheduled between seeing the temporary and the kill,
    // and the build finish first: then it must have written the whole output; try again.
    int status = 0;
    for (int attempt = 1;; ++attempt) {
      const pid_t pid = ::fork();
      ASSERT_GE(pid, 0);
      if (pid == 0) {
        ::execl(LIGHTVOL_EXE, LIGHTVOL_EXE, "build", big.c_str(), "--light", w.light.c_str(),
                "--out", out.c_str(), "--ascii", "--no-check", "--quiet",
                static_cast<char*>(nullptr));
        ::_exit(127);
      }
      // Wait until the temporary exists (a hidden file that is not an input), then signal.
      bool seen = false;
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(3);
      while (!seen && std::chrono::steady_clock::now() < deadline) {
        for (const auto& e : std::filesystem::directory_iterator(w.dir.path()))
          if (e.path().filename().string().rfind(".", 0) == 0) seen = true;
        if (!seen) std::this_thread::sleep_for(std::chrono::microseconds(500));
      }
      ASSERT_TRUE(seen) << "no temporary file appeared";
      ::kill(pid, sig);
      ASSERT_EQ(::waitpid(pid, &status, 0), pid);
      if (WIFSIGNALED(status) || attempt == 5) break;
      ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "signal " << sig;
      ASSERT_TRUE(std::filesystem::exists(out)) << "exited 0 without its output";
      std::filesystem::remove(out);
    }
    ASSERT_TRUE(WIFSIGNALED(status)) << "signal " << sig << ": exited " << WEXITSTATUS(status)
                                     << " five times before the signal came";
    EXPECT_EQ(WTERMSIG(status), sig);
    std::string names;
    for (const auto& e : std::filesystem::directory_iterator(w.dir.path()))
      names += e.path().filename().string() + " ";
    EXPECT_EQ(w.dir.entries(), before) << "signal " << sig << ": " << names;
    EXPECT_FALSE(std::filesystem::exists(out));
  }
}

// Before: a 9x7 image with a light of aspect 1 was accepted silently. Now a warning (stderr and
// the report), and the volume is still built.
TEST(BuildCli, AspectMismatchIsAWarning) {
  Workspace w;
  const std::string square = w.dir.write("square.json", test::spot_json("window", 1.0));
  const std::string report = w.dir.file("r.json");
  const test::CommandResult r =
      test::run_lightvol("build " + q(w.depth) + " --light " + q(square) + " --out " +
                         q(w.dir.file("v.ply")) + " --report " + q(report));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("lightvol: warning: " + w.depth + ": the image is 9x7"), std::string::npos)
      << r.err;
  const nlohmann::json j = nlohmann::json::parse(slurp(report));
  ASSERT_EQ(j["warnings"].size(), 1u);
  EXPECT_NE(j["warnings"][0].get<std::string>().find("aspect 1"), std::string::npos);
  const test::CommandResult matching =
      w.build("--out " + q(w.dir.file("w.ply")) + " --report " + q(report));
  ASSERT_EQ(matching.exit_code, 0) << matching.err;
  EXPECT_EQ(matching.err, "");
  EXPECT_TRUE(nlohmann::json::parse(slurp(report))["warnings"].empty());
}

// Before: --max-error nan and --threshold nan were accepted (a 2-triangle grid 6.5 units off), and
// --max-error inf was refused with a 300-digit number.
TEST(BuildCli, NonFiniteBoundsAreRefused) {
  Workspace w;
  const std::string out = q(w.dir.file("v.ply"));
  const int before = w.dir.entries();
  for (const char* v : {"nan", "inf", "-inf", "NaN", "1e999"}) {
    const test::CommandResult a = w.build("--out " + out + " --adaptive --max-error " + v);
    EXPECT_EQ(a.exit_code, 2) << v << ": " << a.err;
    EXPECT_NE(a.err.find("expected a finite number >= 0"), std::string::npos) << a.err;
    EXPECT_LT(a.err.size(), 200u) << a.err;
    const test::CommandResult t = w.build("--out " + out + " --refine laplacian --threshold " + v);
    EXPECT_EQ(t.exit_code, 2) << v << ": " << t.err;
    EXPECT_NE(t.err.find("expected a finite number >= 0"), std::string::npos) << t.err;
    const test::CommandResult s = test::run_lightvol("stats " + q(w.depth) + " --light " +
                                                     q(w.light) + " --max-error 0.1," + v);
    EXPECT_EQ(s.exit_code, 2) << v << ": " << s.err;
    EXPECT_NE(s.err.find("is not a non-negative number"), std::string::npos) << s.err;
  }
  EXPECT_EQ(w.dir.entries(), before);
}

// Before: --max-error 0x10 was read as 16, --draco-bits 0x10 and --offenders 0x3 as hexadecimal,
// " 3" and +3 were numbers, and --max-memory 1Gb was 1 GiB. Every numeric flag of every command
// reads one way (core/text.h parse_decimal): decimal digits; anything else is refused, naming the
// flag, before anything is read or written.
TEST(BuildCli, EveryNumericFlagIsDecimalOnly) {
  Workspace w;
  const int before = w.dir.entries();
  const std::string out = q(w.dir.file("o.ply")), base = q(w.depth) + " --light " + q(w.light);
  const std::string render = "render " + out + " --light l.json --camera c.json --depth d.exr ";
  const std::pair<std::string, std::string> cases[] = {
      {"build " + base + " --out " + out + " --adaptive --max-error 0x10",
       "--max-error: expected a finite number >= 0 in decimal digits, got '0x10'"},
      {"build " + base + " --out " + out + " --adaptive --max-error +3", "got '+3'"},
      {"build " + base + " --out " + out + " --adaptive --max-error ' 3'", "got ' 3'"},
      {"build " + base + " --out " + out + " --refine laplacian --threshold 1e999",
       "--threshold: expected a finite number >= 0 in decimal digits, got '1e999'"},
      {"build " + base + " --out " + out + " --draco-bits 0x10",
       "--draco-bits: expected a whole number in decimal digits, got '0x10'"},
      {"build " + base + " --out " + out + " --draco-bits 16.0", "--draco-bits: "},
      {"batch jobs.jsonl --jobs 0b11",
       "--jobs: expected a whole number in decimal digits, got '0b11'"},
      {"check " + out + " --offenders 0x3",
       "--offenders: expected a whole number in decimal digits, got '0x3'"},
      {"stats " + base + " --max-error 0.1,0x10",
       "--max-error: '0x10' is not a non-negative number in decimal digits"},
      {"stats " + base + " --max-error inf", "--max-error: 'inf' is not a non-negative number"},
      {render + "--samples 0x10", "--samples: expected a whole number in decimal digits"},
      {render + "--interleave 0o2", "--interleave: expected a whole number in decimal digits"},
      {render + "--frames 1e2", "--frames: expected a whole number in decimal digits"},
      {render + "--background nan", "--background: expected a finite number in decimal digits"},
      {render + "--exposure 0x1p1", "--exposure: expected a finite number in decimal digits"},
      {"demo --out " + q(w.dir.file("demo")) + " --size 0x40",
       "--size: expected a whole number in decimal digits"},
      {"demo --out " + q(w.dir.file("demo")) + " --max-error inf",
       "--max-error: expected a finite number >= 0 in decimal digits"},
      {"check " + out + " --max-memory 1Gb", "--max-memory: '1Gb' is not a memory size"},
      {"check " + out + " --max-memory 0x10M", "--max-memory: '0x10M' is not a memory size"},
  };
  for (const auto& [args, message] : cases) {
    const test::CommandResult r = test::run_lightvol(args);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.err;
    EXPECT_EQ(r.err.rfind("lightvol: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << args << ": " << r.err;
  }
  EXPECT_EQ(w.dir.entries(), before);
}

// --no-check to PLY streams the static volume row by row into the file: the same bytes as the held
// volume written after its check, and the same report.
TEST(BuildCli, StreamedStaticPlyIsTheHeldOneByteForByte) {
  test::TempDir dir;
  const std::string depth = dir.file("d.exr");
  ASSERT_TRUE(write_depth_image(depth, test::make_depth(700, 400,
                                                        [](int c, int r) {
                                                          return 0.9f +
                                                                 0.0001f * static_cast<float>(
                                                                               (c * r) % 700);
                                                        }))
                  .ok());
  for (const std::string& light : {dir.write("spot.json", test::spot_json("window", 7.0 / 4.0)),
                                   dir.write("dir.json", test::directional_json("window"))})
    for (const char* ascii : {"", " --ascii"}) {
      const auto run = [&](const std::string& out, const std::string& flags) {
        const test::CommandResult r =
            test::run_lightvol("build " + q(depth) + " --light " + q(light) + " --out " + q(out) +
                               " --quiet --report " + q(out + ".json") + ascii + flags);
        EXPECT_EQ(r.exit_code, 0) << r.err;
        return nlohmann::json::parse(slurp(out + ".json"));
      };
      const nlohmann::json held = run(dir.file("held.ply"), "");
      const nlohmann::json streamed = run(dir.file("streamed.ply"), " --no-check");
      EXPECT_EQ(slurp(dir.file("held.ply")), slurp(dir.file("streamed.ply"))) << light << ascii;
      for (const char* key : {"vertices", "triangles", "bounds", "volume"})
        EXPECT_EQ(held[key], streamed[key]) << key;
    }
}

// Before: valid lights whose volumes float32 cannot hold gave NaN vertices (written with
// --no-check) or zero-area faces, and exit 1 blaming the volume. Now: exit 2 naming the light's
// keys and the remedy, nothing written; or a volume that passes its checks.
TEST(BuildCli, UnrepresentableLightsAreRefusedNamingTheKey) {
  test::TempDir dir;
  const std::string depth = dir.file("d.exr");
  ASSERT_TRUE(write_depth_image(depth, test::make_depth(64, 64,
                                                        [](int c, int r) {
                                                          return 0.5f +
                                                                 0.004f * static_cast<float>(
                                                                              (c + 2 * r) % 50);
                                                        }))
                  .ok());
  const std::string linear = dir.file("lin.exr");
  ASSERT_TRUE(write_depth_image(linear, test::constant_depth(64, 64, 5.0f)).ok());
  const auto spot = [](const std::string& extra) {
    return std::string(R"({"type": "spot", "direction": [0, -1, 0], "up": [0, 0, -1], )") + extra +
           "}";
  };
  struct Case {
    std::string name, json, image, needle, extra;
  };
  const Case refused[] = {
      {"lin.json",
       spot(
           R"("position": [0, 10, 0], "fov_y_deg": 60, "near": 0.1, "far": 1e18, "depth": "linear")"),
       linear, "keys 'near', 'far' and 'fov_y_deg'", ""},
      {"far_away.json", spot(R"("position": [1e6, 10, 0], "fov_y_deg": 60, "near": 1, "far": 20)"),
       depth, "key 'position'", "--space light"},
      {"deep.json", spot(R"("position": [0, 10, 0], "fov_y_deg": 60, "near": 1e-30, "far": 1e30)"),
       depth, "keys 'near', 'far' and 'fov_y_deg'", ""},
      {"ortho.json",
       R"({"type": "directional", "position": [0, 10, 0], "direction": [0, -1, 0], "up": [0, 0, -1], "ortho": [-1e30, 1e30, -1e30, 1e30], "near": 0, "far": 20})",
       depth, "keys 'ortho', 'near' and 'far'", ""},
  };
  for (const Case& c : refused) {
    const std::string light = dir.write(c.name, c.json);
    for (const char* flags : {"", " --no-check"}) {
      const test::CommandResult r =
          test::run_lightvol("build " + q(c.image) + " --light " + q(light) + " --out " +
                             q(dir.file("v.ply")) + flags);
      EXPECT_EQ(r.exit_code, 2) << c.name << flags << ": " << r.err;
      EXPECT_NE(r.err.find(c.name + ": "), std::string::npos) << r.err;
      EXPECT_NE(r.err.find(c.needle), std::string::npos) << r.err;
      if (!c.extra.empty()) {
        EXPECT_NE(r.err.find(c.extra), std::string::npos) << r.err;
      }
      EXPECT_FALSE(std::filesystem::exists(dir.file("v.ply"))) << c.name;
      std::filesystem::remove(dir.file("v.ply"));
    }
  }
  // The remedy works: the light far from the origin, in its own eye space.
  const test::CommandResult light_space =
      test::run_lightvol("build " + q(depth) + " --light " + q(dir.file("far_away.json")) +
                         " --out " + q(dir.file("l.ply")) + " --space light");
  EXPECT_EQ(light_space.exit_code, 0) << light_space.err;
  // A needle of a frustum (fov 1e-6 degrees): refused naming the keys, never blamed on the volume.
  const std::string needle = dir.write(
      "needle.json", spot(R"("position": [0, 10, 0], "fov_y_deg": 1e-6, "near": 1, "far": 20)"));
  const test::CommandResult thin = test::run_lightvol("build " + q(depth) + " --light " +
                                                      q(needle) + " --out " + q(dir.file("n.ply")));
  EXPECT_EQ(thin.exit_code, 2) << thin.err;
  EXPECT_NE(thin.err.find("keys 'near', 'far' and 'fov_y_deg'"), std::string::npos) << thin.err;
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
