// `lightvol batch` as a user runs it: result lines, bad lines as failed jobs, idempotency by the
// content hash, shards that partition the jobs, no partial output, parallel = serial, SIGINT.
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <lightvol/depth/depth_image.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

using test::q;
using test::slurp;
namespace fs = std::filesystem;

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// A result line without its times (which vary), as compact JSON in the line's key order.
std::string without_seconds(const std::string& line) {
  nlohmann::ordered_json j = nlohmann::ordered_json::parse(line);
  EXPECT_TRUE(j.contains("seconds")) << line;
  for (const auto& [step, seconds] : j["seconds"].items()) EXPECT_GE(seconds.get<double>(), 0);
  j.erase("seconds");
  return j.dump();
}

bool has_temporaries(const std::string& dir) {
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.path().filename().string().rfind(".lv-", 0) == 0) return true;
  return false;
}

// A folder with a jobs file: the 9×7 spot map of the build tests (124 triangles, 64 vertices),
// a second map, a spot light (square texels) and a directional light.
struct Batch {
  test::TempDir dir;
  std::string jobs;
  Batch() {
    jobs = dir.file("jobs.jsonl");
    write_map("a.exr", 0.95f);
    write_map("b.exr", 0.9f);
    dir.write("spot.json", test::spot_json("window", 9.0 / 7.0));
    dir.write("dir.json", test::directional_json());
  }
  void write_map(const std::string& name, float occluder) const {
    const DepthImage d = test::make_depth(9, 7, [occluder](int c, int r) {
      return (c > 2 && c < 6 && r > 1 && r < 5) ? occluder : 0.99f;
    });
    EXPECT_TRUE(write_depth_image(dir.file(name), d).ok());
  }
  void write_jobs(const std::vector<std::string>& lines) const {
    std::string text;
    for (const std::string& l : lines) text += l + "\n";
    dir.write("jobs.jsonl", text);
  }
  test::CommandResult run(const std::string& extra = "") const {
    return test::run_lightvol("batch " + q(jobs) + " --quiet " + extra);
  }
  // `<jobs>:LINE: ` as errors begin.
  std::string at(int line) const { return jobs + ":" + std::to_string(line) + ": "; }
};

std::string job(const std::string& id, const std::string& map, const std::string& out,
                const std::string& args = "", const std::string& light = "spot.json") {
  return R"({"id": ")" + id + R"(", "inputs": [")" + map + R"("], "light": ")" + light +
         R"(", "out": ")" + out + R"(")" + (args.empty() ? "" : ", \"args\": [" + args + "]") + "}";
}

std::string ok_line(int line, const std::string& id, const std::string& out,
                    const std::string& status = "ok") {
  return R"({"line":)" + std::to_string(line) + R"(,"id":")" + id + R"(","status":")" + status +
         R"(","out":")" + out + R"(","vertices":64,"triangles":124,"error":null})";
}

std::string failed_line(int line, const nlohmann::json& id, const nlohmann::json& out,
                        const std::string& error) {
  return R"({"line":)" + std::to_string(line) + R"(,"id":)" + id.dump() +
         R"(,"status":"failed","out":)" + out.dump() +
         R"(,"vertices":null,"triangles":null,"error":)" + nlohmann::json(error).dump() + "}";
}

TEST(BatchCli, ResultLinesForOkFailedAndSkippedJobs) {
  Batch b;
  b.write_jobs({
      "# comment lines and blank lines are not jobs",
      job("a", "a.exr", "a.ply"),
      "",
      "{\"id\": \"x\", \"inputs\": [",
      job("missing", "nope.exr", "m.ply"),
      job("flag", "a.exr", "f.ply", R"("--frobnicate")"),
      job("value", "a.exr", "v.ply", R"("--draco-bits", "99")"),
      job("json", "a.exr", "j.ply", R"("--json")"),
      R"({"inputs": ["a.exr"], "light": "spot.json", "out": "k.ply", "colour": 1})",
      R"({"inputs": "a.exr", "light": "spot.json", "out": "k.ply"})",
      R"({"inputs": ["a.exr"], "out": "k.ply"})",
      job("twice", "b.exr", "a.ply"),
      job("conflict", "a.exr", "c.ply", R"("--max-error", "0.1")"),
      job("b", "b.exr", "b.obj", R"("--adaptive", "--max-error", "0.001")"),
  });
  const test::CommandResult r = b.run("--jobs 3");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err, "");  // --quiet
  const std::vector<std::string> expected = {
      ok_line(2, "a", "a.ply"),
      failed_line(4, nullptr, nullptr, b.at(4) + "not valid JSON (at byte 24)"),
      failed_line(5, "missing", "m.ply",
                  b.at(5) + "key 'inputs': " + b.dir.file("nope.exr") +
                      ": cannot open: No such file or directory"),
      failed_line(6, "flag", "f.ply",
                  b.at(6) + "key 'args': --frobnicate: not a flag of build (see 'lightvol build "
                            "--help')"),
      failed_line(7, "value", "v.ply",
                  b.at(7) + "key 'args': --draco-bits: Value 99 not in range 1 to 30"),
      failed_line(8, "json", "j.ply",
                  b.at(8) + "key 'args': --json: not in a batch (each job's result is a line)"),
      failed_line(9, nullptr, nullptr,
                  b.at(9) + "key 'colour': unknown (a job has id, inputs, light, out, args)"),
      failed_line(10, nullptr, nullptr,
                  b.at(10) + "key 'inputs': expected a non-empty array of paths"),
      failed_line(11, nullptr, nullptr, b.at(11) + "key 'light': expected a path"),
      failed_line(12, "twice", "a.ply",
                  b.at(12) + b.dir.file("a.ply") +
                      ": also an output of line 2; give each job its own out (and report)"),
      failed_line(13, "conflict", "c.ply", b.at(13) + "--max-error: applies with --adaptive only"),
      R"({"line":14,"id":"b","status":"ok","out":"b.obj","vertices":)",
  };
  const std::vector<std::string> lines = lines_of(r.out);
  ASSERT_EQ(lines.size(), expected.size()) << r.out;
  for (std::size_t i = 0; i + 1 < expected.size(); ++i)
    EXPECT_EQ(without_seconds(lines[i]), expected[i]);
  EXPECT_EQ(without_seconds(lines.back()).rfind(expected.back(), 0), 0u) << lines.back();

  // The failed jobs wrote nothing; the two good ones wrote their volumes and reports.
  for (const char* name : {"m.ply", "f.ply", "v.ply", "j.ply", "k.ply", "c.ply"})
    EXPECT_FALSE(fs::exists(b.dir.file(name))) << name;
  EXPECT_TRUE(fs::exists(b.dir.file("a.ply.report.json")));
  EXPECT_TRUE(fs::exists(b.dir.file("b.obj.report.json")));
  EXPECT_FALSE(has_temporaries(b.dir.path()));

  // Again: the good jobs are skipped (with their counts), the bad ones fail the same way.
  const test::CommandResult again = b.run();
  EXPECT_EQ(again.exit_code, 2) << again.err;
  const std::vector<std::string> second = lines_of(again.out);
  ASSERT_EQ(second.size(), expected.size()) << again.out;
  EXPECT_EQ(without_seconds(second[0]), ok_line(2, "a", "a.ply", "skipped"));
  for (std::size_t i = 1; i + 1 < expected.size(); ++i)
    EXPECT_EQ(without_seconds(second[i]), expected[i]);
  EXPECT_EQ(nlohmann::json::parse(second.back())["status"], "skipped");
}

// Runs `lightvol ARGS` under a time limit of its own: timeout(1) kills it (exit 137) after
// `seconds`, so that a batch that hangs fails the test instead of hanging the suite. `before` runs
// first in the same shell (a writer feeding a FIFO in the background).
test::CommandResult run_within(const std::string& args, const std::string& before = "",
                               int seconds = 300) {
  test::TempDir io;
  const std::string out = io.file("stdout"), err = io.file("stderr");
  const std::string command = before + "timeout -s KILL " + std::to_string(seconds) + " '" +
                              LIGHTVOL_EXE + "' " + args + " >'" + out + "' 2>'" + err +
                              "' </dev/null";
  const int status = std::system(command.c_str());
  test::CommandResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

// What `build` refuses, `batch` refuses without hanging: an input that is /dev/zero or a FIFO
// (no writer) is not a regular file; a light that is /dev/zero ends at 64 MiB. A light and a
// medium that are FIFOs fed once are read once: hashed, and those bytes built (the hash used to
// read them, leaving the build's own read blocked).
TEST(BatchCli, DevicesAndPipesAreRefusedOrReadOnceWithoutHanging) {
  Batch b;
  b.dir.write("medium.json", R"({"scattering": 0.05})");
  for (const char* fifo : {"in.fifo", "light.fifo", "medium.fifo"})
    ASSERT_EQ(::mkfifo(b.dir.file(fifo).c_str(), 0600), 0) << fifo;
  b.write_jobs({
      job("zero", "/dev/zero", "z.ply"),
      job("zero light", "a.exr", "zl.ply", "", "/dev/zero"),
      job("fifo", "in.fifo", "f.ply"),
      job("fifo light", "a.exr", "fl.ply", "", "light.fifo"),
      job("fifo medium", "a.exr", "fm.glb", R"("--medium", "medium.fifo")"),
  });
  // Each FIFO that is read gets one writer, which gives up after the batch's own time limit.
  const auto feed = [&](const std::string& from, const std::string& fifo) {
    return "(timeout -s KILL 300 sh -c \"cat '" + b.dir.file(from) + "' > '" + b.dir.file(fifo) +
           "'\" >/dev/null 2>&1 &); ";
  };
  const test::CommandResult r =
      run_within("batch " + q(b.jobs) + " --quiet --jobs 2",
                 feed("spot.json", "light.fifo") + feed("medium.json", "medium.fifo"));
  ASSERT_EQ(r.exit_code, 2) << r.err;
  const std::string not_regular =
      ": is not a regular file (a device or a pipe); images are read from files";
  const std::vector<std::string> lines = lines_of(r.out);
  ASSERT_EQ(lines.size(), 5u) << r.out;
  EXPECT_EQ(without_seconds(lines[0]),
            failed_line(1, "zero", "z.ply", b.at(1) + "key 'inputs': /dev/zero" + not_regular));
  EXPECT_EQ(without_seconds(lines[1]),
            failed_line(2, "zero light", "zl.ply",
                        b.at(2) + "key 'light': /dev/zero: is larger than 64 MiB; a light "
                                  "description is a small JSON file"));
  EXPECT_EQ(without_seconds(lines[2]),
            failed_line(3, "fifo", "f.ply",
                        b.at(3) + "key 'inputs': " + b.dir.file("in.fifo") + not_regular));
  EXPECT_EQ(without_seconds(lines[3]), ok_line(4, "fifo light", "fl.ply"));
  EXPECT_EQ(without_seconds(lines[4]), ok_line(5, "fifo medium", "fm.glb"));
  EXPECT_TRUE(fs::exists(b.dir.file("fl.ply")));
  EXPECT_TRUE(fs::exists(b.dir.file("fm.glb")));
}

TEST(BatchCli, ExitZeroAndASummaryWhenEveryJobIsDone) {
  Batch b;
  b.write_jobs({job("a", "a.exr", "a.ply"), job("d", "a.exr", "d.glb", "", "dir.json")});
  const test::CommandResult r = test::run_lightvol("batch " + q(b.jobs));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(lines_of(r.out).size(), 2u);
  EXPECT_EQ(r.err.rfind("batch: 2 jobs: 2 ok, 0 skipped, 0 failed, ", 0), 0u) << r.err;
  const test::CommandResult again = test::run_lightvol("batch " + q(b.jobs));
  EXPECT_EQ(again.exit_code, 0) << again.err;
  EXPECT_EQ(again.err.rfind("batch: 2 jobs: 0 ok, 2 skipped, 0 failed, ", 0), 0u) << again.err;
  // The report records the job's hash; every output passes check.
  const nlohmann::json report = nlohmann::json::parse(slurp(b.dir.file("d.glb.report.json")));
  EXPECT_EQ(report["job_hash"].get<std::string>().rfind("xxh3-128:", 0), 0u);
  EXPECT_EQ(report["job_hash"].get<std::string>().size(), 9u + 32u);
  EXPECT_EQ(test::run_lightvol("check " + q(b.dir.file("a.ply")) + " --light " +
                               q(b.dir.file("spot.json")) + " --quiet")
                .exit_code,
            0);
}

TEST(BatchCli, BadUsageRunsNothing) {
  Batch b;
  b.write_jobs({job("a", "a.exr", "a.ply")});
  const int before = b.dir.entries();
  for (const char* shard : {"2/2", "1", "-1/2", "a/b", "0/0", "1/2/3", ""}) {
    const test::CommandResult r = b.run("--shard " + q(shard));
    EXPECT_EQ(r.exit_code, 2) << shard;
    EXPECT_EQ(r.out, "");
    EXPECT_EQ(r.err, "lightvol: --shard: expected K/N with 0 <= K < N (e.g. 0/4), got '" +
                         std::string(shard) + "'\n");
  }
  const test::CommandResult missing = test::run_lightvol("batch " + q(b.dir.file("no.jsonl")));
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_EQ(missing.err, "lightvol: " + b.dir.file("no.jsonl") +
                             ": cannot open the jobs file: No such file or directory\n");
  EXPECT_EQ(b.run("--jobs 0").exit_code, 2);
  EXPECT_EQ(b.dir.entries(), before);
}

TEST(BatchCli, ARerunSkipsUnlessAnInputOrOptionChanged) {
  Batch b;
  b.write_jobs({job("a", "a.exr", "a.ply")});
  auto status = [&] {
    const test::CommandResult r = b.run();
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return nlohmann::json::parse(r.out)["status"].get<std::string>();
  };
  EXPECT_EQ(status(), "ok");
  const std::string first = slurp(b.dir.file("a.ply"));
  EXPECT_EQ(status(), "skipped");
  EXPECT_EQ(slurp(b.dir.file("a.ply")), first);

  b.write_map("a.exr", 0.9f);  // the input's bytes
  EXPECT_EQ(status(), "ok");
  EXPECT_NE(slurp(b.dir.file("a.ply")), first);
  EXPECT_EQ(status(), "skipped");

  b.write_jobs({job("a", "a.exr", "a.ply", R"("--space", "light")")});  // an option
  EXPECT_EQ(status(), "ok");
  EXPECT_EQ(status(), "skipped");

  b.dir.write("spot.json", test::spot_json("linear", 9.0 / 7.0));  // the light
  EXPECT_EQ(status(), "ok");
  EXPECT_EQ(status(), "skipped");

  fs::remove(b.dir.file("a.ply.report.json"));  // no report: the output cannot be vouched for
  EXPECT_EQ(status(), "ok");
  fs::remove(b.dir.file("a.ply"));  // no output
  EXPECT_EQ(status(), "ok");
  EXPECT_EQ(status(), "skipped");

  // A report of its own (--report) holds the hash instead of <out>.report.json.
  b.write_jobs({job("a", "a.exr", "a.ply", R"("--report", "a.json")")});
  EXPECT_EQ(status(), "ok");
  EXPECT_TRUE(fs::exists(b.dir.file("a.json")));
  EXPECT_EQ(status(), "skipped");
}

TEST(BatchCli, ShardsPartitionTheJobs) {
  Batch b;
  std::vector<std::string> jobs = {"# not a job"};
  for (int i = 0; i < 8; ++i)
    jobs.push_back(job(std::to_string(i), i % 2 ? "b.exr" : "a.exr", std::to_string(i) + ".ply"));
  jobs.insert(jobs.begin() + 4, "not json");  // a bad line is a job too (number 3)
  b.write_jobs(jobs);
  std::map<int, int> runs_of_line;
  for (int k = 0; k < 3; ++k) {
    const test::CommandResult r = b.run("--shard " + std::to_string(k) + "/3");
    EXPECT_EQ(r.exit_code, k == 0 ? 2 : 0) << r.err;  // job 3 (line 5) is in shard 0
    int number = k;
    for (const std::string& line : lines_of(r.out)) {
      const nlohmann::json j = nlohmann::json::parse(line);
      ++runs_of_line[j["line"].get<int>()];
      // Job i is on line i + 2 (after the comment); the shard holds i = k, k + 3, ...
      EXPECT_EQ(j["line"].get<int>(), number + 2) << line;
      number += 3;
    }
  }
  EXPECT_EQ(runs_of_line.size(), 9u);
  for (const auto& [line, runs] : runs_of_line) EXPECT_EQ(runs, 1) << "line " << line;
  for (int i = 0; i < 8; ++i) EXPECT_TRUE(fs::exists(b.dir.file(std::to_string(i) + ".ply")));
}

// The volume is written, then its report fails (no such folder): the transaction removes the
// volume, so the job leaves nothing; the next job is not affected.
TEST(BatchCli, AFailedJobLeavesNoOutput) {
  Batch b;
  b.write_jobs({job("r", "a.exr", "r.ply", R"("--report", "no/such/folder/r.json")"),
                job("n", "a.exr", "no/n.ply"), job("a", "a.exr", "a.ply")});
  const int before = b.dir.entries();
  const test::CommandResult r = b.run();
  EXPECT_EQ(r.exit_code, 2);
  const std::vector<std::string> lines = lines_of(r.out);
  ASSERT_EQ(lines.size(), 3u) << r.out;
  EXPECT_EQ(nlohmann::json::parse(lines[0])["error"],
            b.at(1) + b.dir.file("no/such/folder/r.json") + ": directory " +
                b.dir.file("no/such/folder") + " does not exist");
  EXPECT_EQ(nlohmann::json::parse(lines[1])["status"], "failed");
  EXPECT_EQ(nlohmann::json::parse(lines[2])["status"], "ok");
  EXPECT_FALSE(fs::exists(b.dir.file("r.ply")));
  EXPECT_EQ(b.dir.entries(), before + 2);  // a.ply and its report
}

TEST(BatchCli, ParallelAndSerialRunsWriteTheSameBytes) {
  Batch serial, parallel;
  const std::vector<std::string> jobs = {
      job("s", "a.exr", "s.ply"),
      job("a", "b.exr", "a.glb", R"("--adaptive", "--max-error", "0.001")"),
      job("d", "a.exr", "d.obj", "", "dir.json"),
      job("l", "b.exr", "l.off", R"("--space", "light")"),
      job("t", "a.exr", "t.stl", R"("--ascii")"),
      job("q", "b.exr", "q.ply",
          R"("--adaptive", "--max-error", "0", "--tessellation", "quadtree")"),
  };
  serial.write_jobs(jobs);
  parallel.write_jobs(jobs);
  ASSERT_EQ(serial.run("--jobs 1").exit_code, 0);
  ASSERT_EQ(parallel.run("--jobs 6").exit_code, 0);
  for (const char* out : {"s.ply", "a.glb", "d.obj", "l.off", "t.stl", "q.ply"}) {
    const std::string bytes = slurp(serial.dir.file(out));
    EXPECT_FALSE(bytes.empty()) << out;
    EXPECT_EQ(bytes, slurp(parallel.dir.file(out))) << out;
  }
}

TEST(BatchCli, ResultsFileInsteadOfStdout) {
  Batch b;
  b.write_jobs({job("a", "a.exr", "a.ply"), "oops"});
  const test::CommandResult r = b.run("--results " + q(b.dir.file("results.jsonl")));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.out, "");
  const std::vector<std::string> lines = lines_of(slurp(b.dir.file("results.jsonl")));
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(without_seconds(lines[0]), ok_line(1, "a", "a.ply"));
  EXPECT_EQ(nlohmann::json::parse(lines[1])["status"], "failed");
}

// Before: --results /dev/stdout with stdout redirected to a file renamed a temporary over the
// /dev/stdout symlink (not run on that code: it harms the machine).
TEST(BatchCli, ResultsOnStandardOutput) {
  Batch b;
  b.write_jobs({job("a", "a.exr", "a.ply")});
  for (const std::string results : {"/dev/stdout", "-"}) {
    const test::CommandResult r = b.run("--results " + results);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const std::vector<std::string> lines = lines_of(r.out);
    ASSERT_EQ(lines.size(), 1u) << r.out;
    EXPECT_EQ(nlohmann::json::parse(lines[0])["out"], "a.ply");
    EXPECT_TRUE(fs::is_symlink("/dev/stdout"));
  }
  b.write_jobs({R"({"inputs": ["a.exr"], "light": "spot.json", "out": "c.ply", "args": )"
                R"(["--report", "-"]})"});
  const test::CommandResult r = b.run();
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("--report -: a job's report is a file"), std::string::npos) << r.out;
}

// Before: a job in a Latin-1 folder aborted the whole batch (exit 134) as its report or result
// line was made; so did a helper's refusal quoting such a path, and a light whose long non-ASCII
// value was cut inside a character.
TEST(BatchCli, NonUtf8TextNeverAbortsABatch) {
  Batch b;
  const std::string folder = b.dir.file("caf\xe9");
  ASSERT_TRUE(fs::create_directory(folder));
  for (const char* name : {"a.exr", "spot.json"})
    fs::copy_file(b.dir.file(name), folder + "/" + name);
  std::ofstream(folder + "/bad.exr") << "not an image";
  std::string e60;
  for (int i = 0; i < 60; ++i) e60 += "\xc3\xa9";
  std::ofstream(folder + "/long.json") << R"({"type": ")" + e60 + R"("})";
  std::ofstream(folder + "/jobs.jsonl") << job("ok", "a.exr", "a.ply") << "\n"
                                        << job("bad", "bad.exr", "b.ply") << "\n"
                                        << job("long", "a.exr", "c.ply", "", "long.json") << "\n";
  const test::CommandResult r = test::run_lightvol("batch " + q(folder + "/jobs.jsonl") + " -q");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const std::vector<std::string> lines = lines_of(r.out);
  ASSERT_EQ(lines.size(), 3u) << r.out;
  const std::string shown = b.dir.path() + "/caf\xef\xbf\xbd/";
  EXPECT_EQ(without_seconds(lines[0]), ok_line(1, "ok", "a.ply"));
  const nlohmann::json bad = nlohmann::json::parse(lines[1]);
  EXPECT_EQ(bad["status"], "failed");
  EXPECT_EQ(
      bad["error"].get<std::string>().rfind(shown + "jobs.jsonl:2: " + shown + "bad.exr: ", 0), 0u)
      << lines[1];
  const nlohmann::json long_light = nlohmann::json::parse(lines[2]);
  EXPECT_EQ(long_light["status"], "failed");
  EXPECT_NE(long_light["error"].get<std::string>().find("got \"\xc3\xa9"), std::string::npos)
      << lines[2];
  EXPECT_EQ(nlohmann::json::parse(slurp(folder + "/a.ply.report.json"))["output"], shown + "a.ply");
  EXPECT_FALSE(has_temporaries(folder));
}

// Before: "v\u0000.ply" wrote the volume and its report both to "v" (the report over the volume)
// and the job said ok.
TEST(BatchCli, ControlCharactersInPathsAreRefusedNamingLineAndKey) {
  Batch b;
  b.write_jobs({R"({"inputs": ["a.exr"], "light": "spot.json", "out": "v\u0000.ply"})",
                R"({"inputs": ["a\n.exr"], "light": "spot.json", "out": "w.ply"})",
                R"({"inputs": ["a.exr"], "light": "spot.json", "out": "x.ply", )"
                R"("args": ["--report", "r\u001b.json"]})"});
  const int before = b.dir.entries();
  const test::CommandResult r = b.run();
  EXPECT_EQ(r.exit_code, 2);
  const std::vector<std::string> lines = lines_of(r.out);
  ASSERT_EQ(lines.size(), 3u) << r.out;
  const std::string where = b.jobs + ":";
  EXPECT_EQ(nlohmann::json::parse(lines[0])["error"],
            where +
                "1: key 'out': control character \\x00 at byte 1; paths and flags may not "
                "hold one");
  EXPECT_EQ(nlohmann::json::parse(lines[1])["error"],
            where +
                "2: key 'inputs': control character \\x0a at byte 1; paths and flags may not "
                "hold one");
  EXPECT_EQ(nlohmann::json::parse(lines[2])["error"],
            where +
                "3: key 'args': control character \\x1b at byte 1; paths and flags may not "
                "hold one");
  EXPECT_EQ(b.dir.entries(), before);
}

// Before: --results naming a job's output replaced the volume with result lines (and a rerun
// skipped the job), --results over the jobs file or a light destroyed it, and a job could write
// its report over another job's light or its out over the jobs file.
TEST(BatchCli, NoOutputReplacesAnInputOrAnotherOutput) {
  Batch b;
  b.write_jobs({job("a", "a.exr", "a.ply")});
  const std::string jobs_text = slurp(b.jobs), light_text = slurp(b.dir.file("spot.json"));
  const int before = b.dir.entries();
  struct Case {
    std::string results, message;
  };
  for (const Case& c :
       {Case{"a.ply", ": is also an output of line 1; give the results their own file"},
        Case{"a.ply.report.json", ": is also an output of line 1; give the results their own file"},
        Case{"jobs.jsonl", ": is also the jobs file; an output may not replace an input"},
        Case{"spot.json", ": is also " + b.dir.file("spot.json") +
                              ", an input of line 1 (key 'light'); an output may not replace an "
                              "input"}}) {
    const test::CommandResult r = b.run("--results " + q(b.dir.file(c.results)));
    EXPECT_EQ(r.exit_code, 2) << c.results;
    EXPECT_EQ(r.out, "");
    EXPECT_EQ(r.err, "lightvol: --results " + b.dir.file(c.results) + c.message + "\n");
    EXPECT_EQ(b.dir.entries(), before) << c.results;  // nothing ran, nothing was written
  }
  EXPECT_EQ(slurp(b.jobs), jobs_text);

  // A job's report over another job's light; a jobs file named like a job's out.
  b.write_jobs(
      {job("a", "a.exr", "a.ply"), job("b", "b.exr", "b.ply", R"("--report", "spot.json")")});
  test::CommandResult r = b.run();
  EXPECT_EQ(r.exit_code, 2);
  std::vector<std::string> lines = lines_of(r.out);
  ASSERT_EQ(lines.size(), 2u) << r.out;
  EXPECT_EQ(nlohmann::json::parse(lines[0])["status"], "ok");
  EXPECT_EQ(nlohmann::json::parse(lines[1])["error"],
            b.jobs + ":2: " + b.dir.file("spot.json") + ": is also " + b.dir.file("spot.json") +
                ", an input of line 1 (key 'light'); an output may not replace an input");
  EXPECT_EQ(slurp(b.dir.file("spot.json")), light_text);

  const std::string jobs_ply = b.dir.write("jobs.ply", job("c", "a.exr", "jobs.ply") + "\n");
  r = test::run_lightvol("batch " + q(jobs_ply) + " -q");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(nlohmann::json::parse(r.out)["error"],
            jobs_ply + ":1: " + jobs_ply +
                ": is also the jobs file; an output may not replace an "
                "input");
  EXPECT_EQ(slurp(jobs_ply), job("c", "a.exr", "jobs.ply") + "\n");
}

// SIGINT while jobs run: the process dies of it, no temporary is left, and every volume that
// appeared is whole, with its report; a rerun skips those and builds the rest.
TEST(BatchCli, InterruptedBatchLeavesOnlyWholeOutputs) {
  Batch b;
  ASSERT_TRUE(write_depth_image(
                  b.dir.file("big.exr"),
                  test::make_depth(400, 400,
                                   [](int c, int r) {
                                     return 0.9f +
                                            0.05f * static_cast<float>((c * 7 + r * 3) % 17) / 17;
                                   }))
                  .ok());
  b.dir.write("square.json", test::spot_json());
  fs::create_directory(b.dir.file("out"));
  std::vector<std::string> jobs;
  for (int i = 0; i < 12; ++i)
    jobs.push_back(job(std::to_string(i), "big.exr", "out/" + std::to_string(i) + ".ply",
                       R"("--ascii")", "square.json"));
  b.write_jobs(jobs);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::execl(LIGHTVOL_EXE, LIGHTVOL_EXE, "batch", b.jobs.c_str(), "--quiet", "--jobs", "2",
            "--results", b.dir.file("results.jsonl").c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  bool seen = false;  // a temporary in out/
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(3);
  while (!seen && std::chrono::steady_clock::now() < deadline) {
    seen = has_temporaries(b.dir.file("out"));
    if (!seen) std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  ASSERT_TRUE(seen) << "no temporary file appeared";
  ::kill(pid, SIGINT);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(status)) << "exited " << WEXITSTATUS(status);
  EXPECT_EQ(WTERMSIG(status), SIGINT);
  EXPECT_FALSE(has_temporaries(b.dir.path()));
  EXPECT_FALSE(fs::exists(b.dir.file("results.jsonl")));
  int done = 0;
  for (int i = 0; i < 12; ++i) {
    const std::string out = b.dir.file("out/" + std::to_string(i) + ".ply");
    EXPECT_EQ(fs::exists(out), fs::exists(out + ".report.json")) << out;
    if (!fs::exists(out)) continue;
    ++done;
    EXPECT_EQ(test::run_lightvol("check " + q(out) + " --light " + q(b.dir.file("square.json")) +
                                 " --quiet")
                  .exit_code,
              0)
        << out;
  }
  EXPECT_LT(done, 12);
  const test::CommandResult rerun = test::run_lightvol("batch " + q(b.jobs));
  EXPECT_EQ(rerun.exit_code, 0) << rerun.err;
  EXPECT_NE(rerun.err.find(": " + std::to_string(12 - done) + " ok, " + std::to_string(done) +
                           " skipped, 0 failed"),
            std::string::npos)
      << rerun.err;
}

// Before: a jobs file of /dev/zero grew without bound, and a FIFO was read as it came. A jobs
// file is a regular file of at most 256 MiB, as build's inputs are regular files; each refusal
// names the file, and nothing runs.
TEST(BatchCli, TheJobsFileIsARegularFileOfAtMost256MiB) {
  Batch b;
  const std::string fifo = b.dir.file("jobs.fifo"), big = b.dir.file("big.jsonl");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  {
    std::ofstream out(big);
    out << job("a", "a.exr", "a.ply") << "\n";
  }
  fs::resize_file(big, (std::uintmax_t{256} << 20) + 1);  // sparse: no disk used
  const int before = b.dir.entries();
  const std::string not_regular =
      ": is not a regular file (a device or a pipe); a jobs file is read from a file\n";
  const std::pair<std::string, std::string> cases[] = {
      {"/dev/zero", "lightvol: /dev/zero" + not_regular},
      {fifo, "lightvol: " + fifo + not_regular},
      {b.dir.path(), "lightvol: " + b.dir.path() + ": is a directory, not a jobs file\n"},
      {big,
       "lightvol: " + big + ": is larger than 256 MiB, the most a jobs file may hold; split it\n"},
  };
  for (const auto& [jobs, message] : cases) {
    const test::CommandResult r = run_within("batch " + q(jobs), "", 120);
    EXPECT_EQ(r.exit_code, 2) << jobs;
    EXPECT_EQ(r.out, "");
    EXPECT_EQ(r.err, message);
  }
  EXPECT_EQ(b.dir.entries(), before);
}

// Before: args ["--report"] took batch's own "--" as its path and wrote a file named "--"; a
// flag that needs a value is refused when none follows it, naming the line and the flag.
TEST(BatchCli, AFlagWithoutItsValueIsRefusedNamingTheLineAndTheFlag) {
  Batch b;
  b.write_jobs({job("r", "a.exr", "r.ply", R"("--report")"), job("o", "a.exr", "o.ply", R"("-o")"),
                job("m", "a.exr", "m.ply", R"("--adaptive", "--max-error")"),
                job("c", "a.exr", "c.ply", R"("--report", "c.json", "--channel")"),
                job("ok", "a.exr", "k.ply", R"("--report", "k.json")")});
  const int before = b.dir.entries();
  const test::CommandResult r = b.run();
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const std::vector<std::string> lines = lines_of(r.out);
  ASSERT_EQ(lines.size(), 5u) << r.out;
  const char* flags[] = {"--report", "-o", "--max-error", "--channel"};
  const char* ids[] = {"r", "o", "m", "c"};
  const char* outs[] = {"r.ply", "o.ply", "m.ply", "c.ply"};
  for (int i = 0; i < 4; ++i)
    EXPECT_EQ(without_seconds(lines[i]), failed_line(i + 1, ids[i], outs[i],
                                                     b.at(i + 1) + "key 'args': " + flags[i] +
                                                         ": needs a value, and none follows it"));
  EXPECT_EQ(nlohmann::json::parse(lines[4])["status"], "ok");
  EXPECT_FALSE(fs::exists(b.dir.file("--")));
  EXPECT_EQ(b.dir.entries(), before + 2);  // k.ply and k.json
}

// Before: a line with "out" twice used the last one. Every key is given once, as in a light file.
TEST(BatchCli, ARepeatedKeyIsRefusedNamingTheLineAndTheKey) {
  Batch b;
  b.write_jobs({
      R"({"inputs": ["a.exr"], "light": "spot.json", "out": "x.ply", "out": "y.ply"})",
      R"({"id": "a", "id": "b", "inputs": ["a.exr"], "light": "spot.json", "out": "z.ply"})",
      R"({"inputs": ["a.exr"], "args": [], "light": "spot.json", "out": "w.ply", "args": []})",
      R"({"inputs": ["a.exr"], "light": "spot.json", "out": "v.ply"})",
  });
  const test::CommandResult r = b.run();
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const std::vector<std::string> lines = lines_of(r.out);
  ASSERT_EQ(lines.size(), 4u) << r.out;
  const char* keys[] = {"out", "id", "args"};
  for (int i = 0; i < 3; ++i)
    EXPECT_EQ(without_seconds(lines[i]),
              failed_line(
                  i + 1, nullptr, nullptr,
                  b.at(i + 1) + "key '" + keys[i] + "': given twice (a job gives each key once)"));
  EXPECT_EQ(nlohmann::json::parse(lines[3])["status"], "ok");
  for (const char* name : {"x.ply", "y.ply", "z.ply", "w.ply"})
    EXPECT_FALSE(fs::exists(b.dir.file(name))) << name;
}

// Before: a rerun skipped an output someone had truncated (the report's hash vouches for the
// inputs). The report records the output's size and hash; a rerun skips only an output that
// still has them, else it builds it again.
TEST(BatchCli, ARerunRebuildsAnOutputThatNoLongerHasItsBytes) {
  Batch b;
  b.write_jobs({job("a", "a.exr", "a.ply")});
  auto status = [&] {
    const test::CommandResult r = b.run();
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json line = nlohmann::json::parse(r.out);
    EXPECT_EQ(line["vertices"], 64) << r.out;
    EXPECT_EQ(line["triangles"], 124) << r.out;
    return line["status"].get<std::string>();
  };
  EXPECT_EQ(status(), "ok");
  const std::string volume = slurp(b.dir.file("a.ply"));
  const nlohmann::json report = nlohmann::json::parse(slurp(b.dir.file("a.ply.report.json")));
  EXPECT_EQ(report["output_bytes"], volume.size());
  EXPECT_EQ(report["output_hash"].get<std::string>().rfind("xxh3-128:", 0), 0u);
  EXPECT_EQ(status(), "skipped");

  fs::resize_file(b.dir.file("a.ply"), volume.size() / 2);  // truncated
  EXPECT_EQ(status(), "ok");
  EXPECT_EQ(slurp(b.dir.file("a.ply")), volume);
  std::string flipped = volume;  // the same size, one byte changed
  flipped[flipped.size() - 5] ^= 1;
  b.dir.write("a.ply", flipped);
  EXPECT_EQ(status(), "ok");
  EXPECT_EQ(slurp(b.dir.file("a.ply")), volume);
  EXPECT_EQ(status(), "skipped");
}

// Before: a report with "vertices": "many" failed the job with nlohmann's message, and -5 printed
// as 18446744073709551611. A report that cannot be trusted vouches for nothing: the job is built
// again (and its report written anew), as if there were none.
TEST(BatchCli, AReportThatCannotBeTrustedMeansTheJobRunsAgain) {
  Batch b;
  b.write_jobs({job("a", "a.exr", "a.ply")});
  ASSERT_EQ(b.run().exit_code, 0);
  const std::string report_path = b.dir.file("a.ply.report.json");
  const nlohmann::json good = nlohmann::json::parse(slurp(report_path));
  auto edited = [&](const char* key, const nlohmann::json& value) {
    nlohmann::json r = good;
    if (value.is_discarded())
      r.erase(key);
    else
      r[key] = value;
    return r.dump();
  };
  const nlohmann::json gone = nlohmann::json(nlohmann::json::value_t::discarded);
  const std::string reports[] = {
      edited("vertices", "many"),
      edited("vertices", -5),
      edited("triangles", 1.5),
      edited("triangles", nullptr),
      edited("vertices", gone),
      edited("job_hash", 7),
      edited("output_bytes", -1),
      edited("output_hash", gone),
      "[1, 2]",
      "{\"vertices\": ",
      std::string(100, '['),
  };
  for (const std::string& report : reports) {
    b.dir.write("a.ply.report.json", report);
    const test::CommandResult r = b.run();
    EXPECT_EQ(r.exit_code, 0) << report << ": " << r.err;
    EXPECT_EQ(without_seconds(r.out), ok_line(1, "a", "a.ply")) << report;
    EXPECT_EQ(nlohmann::json::parse(slurp(report_path))["job_hash"], good["job_hash"]);
  }
  const test::CommandResult again = b.run();
  EXPECT_EQ(without_seconds(again.out), ok_line(1, "a", "a.ply", "skipped"));
}

// Temporaries of lightvol's naming left by a killed run (SIGKILL cannot be cleaned up after) are
// removed by the next run that writes into their folder, once they are an hour old; a younger one
// may be a live writer's and stays, as does a file of another naming or with a second link.
TEST(BatchCli, StaleTemporariesOfAKilledRunAreRemovedByTheNextRun) {
  Batch b;
  b.write_jobs({job("a", "a.exr", "a.ply")});
  const auto two_hours_ago = fs::file_time_type::clock::now() - std::chrono::hours(2);
  const std::string stale = b.dir.file(".lv-0123456789abcdef.ply");
  const std::string stale_report = b.dir.file(".lv-zyxwvutsrqponmlk.json");
  const std::string bare = b.dir.file(".lv-aaaaaaaaaaaaaaaa");
  const std::string fresh = b.dir.file(".lv-fedcba9876543210.ply");
  const std::string other = b.dir.file(".lv-notours.ply");
  const std::string linked = b.dir.file(".lv-1111111111111111.ply");
  for (const std::string& path : {stale, stale_report, bare, fresh, other, linked})
    b.dir.write(fs::path(path).filename().string(), "partial");
  ASSERT_EQ(::link(linked.c_str(), b.dir.file("keep.ply").c_str()), 0);
  for (const std::string& path : {stale, stale_report, bare, other, linked})
    fs::last_write_time(path, two_hours_ago);
  const test::CommandResult r = b.run();
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::exists(stale));
  EXPECT_FALSE(fs::exists(stale_report));
  EXPECT_FALSE(fs::exists(bare));
  EXPECT_TRUE(fs::exists(fresh));   // may be a live writer's
  EXPECT_TRUE(fs::exists(other));   // not our naming
  EXPECT_TRUE(fs::exists(linked));  // a second link: a backup a commit may still need
  EXPECT_TRUE(fs::exists(b.dir.file("a.ply")));
}

// Before: the content hash was taken before the build read the map (lightvol-image opens it by
// path), so a map replaced in between left a report whose hash vouched for other bytes than the
// volume's. Now each map is checked after the build's read: unchanged, or the job fails and
// writes nothing. A writer flips the map between two contents while jobs run; every volume
// written must be the one its report's hash stands for.
TEST(BatchCli, AMapReplacedWhileAJobReadsItNeverLeavesAReportForOtherBytes) {
  Batch b;
  // The two contents, and the volume and job hash of each (the hash covers the out's format, not
  // its name: every job below has the same hash for the same map).
  b.write_map("map_a.exr", 0.95f);
  b.write_map("map_b.exr", 0.5f);
  std::map<std::string, std::string> volume_of_hash;
  for (const char* map : {"map_a.exr", "map_b.exr"}) {
    fs::copy_file(b.dir.file(map), b.dir.file("m.exr"), fs::copy_options::overwrite_existing);
    b.write_jobs({job("ref", "m.exr", "ref.ply")});
    ASSERT_EQ(b.run().exit_code, 0);
    const nlohmann::json report = nlohmann::json::parse(slurp(b.dir.file("ref.ply.report.json")));
    volume_of_hash[report["job_hash"]] = slurp(b.dir.file("ref.ply"));
    fs::remove(b.dir.file("ref.ply"));
  }
  ASSERT_EQ(volume_of_hash.size(), 2u);
  ASSERT_NE(volume_of_hash.begin()->second, volume_of_hash.rbegin()->second);

  std::vector<std::string> jobs;
  for (int i = 0; i < 12; ++i)
    jobs.push_back(job(std::to_string(i), "m.exr", "o" + std::to_string(i) + ".ply"));
  b.write_jobs(jobs);
  std::atomic<bool> stop{false};
  std::thread writer([&] {  // m.exr becomes the other map, by a rename, again and again
    for (int flip = 0; !stop; ++flip) {
      const std::string from = b.dir.file(flip % 2 ? "map_a.exr" : "map_b.exr");
      const std::string temp = b.dir.file("m.tmp");
      fs::remove(temp);
      if (::link(from.c_str(), temp.c_str()) == 0)
        ::rename(temp.c_str(), b.dir.file("m.exr").c_str());
      std::this_thread::sleep_for(std::chrono::milliseconds(3));
    }
  });
  int written = 0;
  for (int round = 0; round < 3; ++round) {
    for (int i = 0; i < 12; ++i) fs::remove(b.dir.file("o" + std::to_string(i) + ".ply"));
    const test::CommandResult r = b.run("--jobs 4");
    for (const std::string& line : lines_of(r.out)) {
      const nlohmann::json result = nlohmann::json::parse(line);
      const std::string out = b.dir.file(result["out"].get<std::string>());
      if (result["status"] != "ok") {
        EXPECT_FALSE(fs::exists(out)) << line;
        continue;
      }
      ++written;
      const nlohmann::json report = nlohmann::json::parse(slurp(out + ".report.json"));
      const auto expected = volume_of_hash.find(report["job_hash"].get<std::string>());
      ASSERT_NE(expected, volume_of_hash.end()) << line;
      EXPECT_EQ(slurp(out), expected->second) << line << ": the volume is of other bytes";
    }
  }
  stop = true;
  writer.join();
  std::printf("%d of 36 jobs wrote a volume while the map changed under them\n", written);
}

}  // namespace
}  // namespace lightvol
