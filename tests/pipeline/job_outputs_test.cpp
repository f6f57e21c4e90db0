// pipeline/: refuse_clashing_outputs, the batch's check that no output replaces another job's
// output, an input or the jobs file, with the message that names both.
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/pipeline/build_job.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

// A job of jobs.jsonl's line `line` reading `depth` and `light`, writing `out` and its report.
BuildJob job(int line, const std::string& depth, const std::string& light, const std::string& out) {
  BuildJob b;
  b.line = line;
  b.where = "jobs.jsonl:" + std::to_string(line);
  b.options.depth_paths = {depth};
  b.options.light_path = light;
  b.options.out_path = out;
  b.options.report_path = out + ".report.json";
  return b;
}

TEST(JobOutputs, TwoJobsWritingOneFileRefuseTheLaterOneNamingTheEarlierLine) {
  const test::TempDir dir;
  const std::string jobs = dir.file("jobs.jsonl");
  BuildJob a = job(1, dir.file("a.exr"), dir.file("light.json"), dir.file("v.ply"));
  BuildJob b = job(3, dir.file("b.exr"), dir.file("light.json"), dir.file("v.ply"));
  BuildJob c = job(4, dir.file("c.exr"), dir.file("light.json"), dir.file("w.ply"));
  ASSERT_TRUE(refuse_clashing_outputs({&a, &b, &c}, {jobs, ""}).ok());
  EXPECT_EQ(a.refused, "");
  EXPECT_EQ(b.refused, "jobs.jsonl:3: " + dir.file("v.ply") +
                           ": also an output of line 1; give each job its own out (and report)");
  EXPECT_EQ(c.refused, "");
}

TEST(JobOutputs, AnOutputThatIsAnInputOrTheJobsFileIsRefused) {
  const test::TempDir dir;
  const std::string jobs = dir.file("jobs.jsonl");
  BuildJob a = job(1, dir.file("a.exr"), dir.file("light.json"), dir.file("v.ply"));
  BuildJob b = job(2, dir.file("b.exr"), dir.file("light.json"), dir.file("a.exr"));
  BuildJob c = job(5, dir.file("c.exr"), dir.file("light.json"), jobs);
  ASSERT_TRUE(refuse_clashing_outputs({&a, &b, &c}, {jobs, ""}).ok());
  EXPECT_EQ(a.refused, "");
  EXPECT_EQ(b.refused, "jobs.jsonl:2: " + dir.file("a.exr") + ": is also " + dir.file("a.exr") +
                           ", an input of line 1 (key 'inputs'); an output may not replace an "
                           "input");
  EXPECT_EQ(c.refused, "jobs.jsonl:5: " + jobs +
                           ": is also the jobs file; an output may not replace an input");
}

TEST(JobOutputs, RefusedJobsTakePartNeitherAsOutputsNorAsInputs) {
  const test::TempDir dir;
  BuildJob a = job(1, dir.file("a.exr"), dir.file("light.json"), dir.file("v.ply"));
  a.refused = "jobs.jsonl:1: key 'light': missing";
  BuildJob b = job(2, dir.file("b.exr"), dir.file("light.json"), dir.file("v.ply"));
  BuildJob c = job(3, dir.file("c.exr"), dir.file("light.json"), dir.file("a.exr"));
  ASSERT_TRUE(refuse_clashing_outputs({&a, &b, &c}, {dir.file("jobs.jsonl"), ""}).ok());
  EXPECT_EQ(a.refused, "jobs.jsonl:1: key 'light': missing");
  EXPECT_EQ(b.refused, "");
  EXPECT_EQ(c.refused, "");
}

TEST(JobOutputs, AResultsFileThatIsAnInputOrAnOutputIsAnError) {
  const test::TempDir dir;
  const std::string jobs = dir.file("jobs.jsonl");
  BuildJob a = job(2, dir.file("a.exr"), dir.file("light.json"), dir.file("v.ply"));
  Status s = refuse_clashing_outputs({&a}, {jobs, dir.file("light.json")});
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().message, "BatchFiles::results_path " + dir.file("light.json") + ": is also " +
                                   dir.file("light.json") +
                                   ", an input of line 2 (key 'light'); an output may not "
                                   "replace an input");
  s = refuse_clashing_outputs({&a}, {jobs, dir.file("v.ply.report.json")});
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().message, "BatchFiles::results_path " + dir.file("v.ply.report.json") +
                                   ": is also an output of line 2; give the results their own "
                                   "file");
  EXPECT_TRUE(refuse_clashing_outputs({&a}, {jobs, dir.file("results.jsonl")}).ok());
}

}  // namespace
}  // namespace lightvol
