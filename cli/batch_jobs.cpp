// The jobs file of `lightvol batch` (docs/batch.md) as build command lines: each line's arguments
// parsed by build's own flag definitions (build_flags.h), its paths resolved against the jobs
// file's folder, and the outputs of the run checked against each other and against its inputs
// (refuse_clashing_outputs, pipeline/build_job.h).
#include "batch_jobs.h"

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <lightvol/core/jobs_file.h>

#include "commands.h"

namespace lightvol::cli {
namespace {
namespace fs = std::filesystem;
using ordered_json = nlohmann::ordered_json;

std::string resolve(const fs::path& base, const std::string& path) {
  if (path.empty() || fs::path(path).is_absolute() || base.empty()) return path;
  return (base / path).string();
}

// A flag of `app` that needs a value, given last in `args` with none: batch's own "--" (which
// ends the flags of a job's line) would be its value (["--report"] used to write a file named
// "--"). Also any option that took a "--" as its value once parsed. "" when there is none.
std::string flag_without_value(const CLI::App& app, const std::vector<std::string>& args) {
  if (!args.empty()) {
    const std::string& last = args.back();
    if (last.size() > 1 && last[0] == '-' && last != "--" && last.find('=') == std::string::npos)
      if (const CLI::Option* option = app.get_option_no_throw(last);
          option && option->get_items_expected_min() > 0)
        return last;
  }
  for (const CLI::Option* option : app.get_options())
    for (const std::string& value : option->results())
      if (value == "--") return option->get_name();
  return "";
}

// A job line's `args` parsed by build's own option definitions, its paths resolved against
// `base`; `where` ("<jobs file>:<line>") begins its errors.
Job parse_job(const JobLine& line, const std::string& where, const fs::path& base) {
  Job job;
  job.line = line.line;
  job.number = line.number;
  if (line.id) job.id = *line.id;
  if (line.out) job.out = *line.out;
  job.error = line.error;
  if (!job.error.empty()) return job;
  auto bad = [&](const std::string& why) {
    job.error = where + ": " + why;
    return job;
  };
  // build's command line: the flags first, then "--" and the inputs (a path may start with '-').
  std::vector<std::string> argv = {"--light", line.light, "--out", *line.out};
  argv.insert(argv.end(), line.args.begin(), line.args.end());
  argv.push_back("--");
  argv.insert(argv.end(), line.inputs.begin(), line.inputs.end());
  std::reverse(argv.begin(), argv.end());  // CLI11 takes them last first
  CLI::App build{"build"};
  build.name("build");
  build.set_help_flag();
  BuildCommandOptions& o = job.options;
  add_build_options(build, o);
  build.allow_extras();  // an unknown flag is named below
  if (const std::string flag = flag_without_value(build, line.args); !flag.empty())
    return bad("key 'args': " + flag + ": needs a value, and none follows it");
  try {
    build.parse(argv);
  } catch (const CLI::ParseError& e) {
    return bad("key 'args': " + std::string(e.what()));
  }
  if (const std::string flag = flag_without_value(build, {}); !flag.empty())
    return bad("key 'args': " + flag + ": needs a value, and none follows it");
  for (const std::string& extra : build.remaining())
    if (extra != "--")
      return bad("key 'args': " + extra + ": not a flag of build (see 'lightvol build --help')");
  if (o.json) return bad("key 'args': --json: not in a batch (each job's result is a line)");
  if (o.report_path == "-")
    return bad(
        "key 'args': --report -: a job's report is a file (batch reads it back to skip "
        "the job when nothing changed)");
  o.quiet = true;
  for (std::string& p : o.depth_paths) p = resolve(base, p);
  o.light_path = resolve(base, o.light_path);
  o.out_path = resolve(base, o.out_path);
  o.medium_path = resolve(base, o.medium_path);
  // Every job writes a report: it holds the content hash that makes a rerun skip the job.
  o.report_path =
      o.report_path.empty() ? o.out_path + ".report.json" : resolve(base, o.report_path);
  return job;
}

// Every job of the jobs file at `jobs_path`, in order, so that a job's number, and so its shard,
// is the same in every shard.
Result<std::vector<Job>> read_jobs(const std::string& jobs_path) {
  Result<std::string> text = read_jobs_file(jobs_path);
  if (!text) return text.error();
  Result<std::vector<JobLine>> lines = parse_jobs_text(*text, jobs_path);
  if (!lines) return lines.error();
  *text = std::string();
  const fs::path base = fs::path(jobs_path).parent_path();
  std::vector<Job> all;
  all.reserve(lines->size());
  for (const JobLine& line : *lines)
    all.push_back(parse_job(line, job_where(jobs_path, line.line), base));
  return all;
}

// The library's job for `job`, which "<jobs file>:<line>" names, before its flags become the
// build's options: its files only (what refuse_clashing_outputs compares).
BuildJob job_files(const Job& job, const std::string& where) {
  BuildJob b;
  b.where = where;
  b.line = job.line;
  b.refused = job.error;
  if (!job.error.empty()) return b;
  const BuildCommandOptions& o = job.options;
  b.options.depth_paths = o.depth_paths;
  b.options.light_path = o.light_path;
  b.options.medium_path = o.medium_path;
  b.options.out_path = o.out_path;
  b.options.report_path = o.report_path;
  return b;
}

// `b` with the build's options of `job`'s flags, or refused with the flags that conflict.
void set_build_options(const Job& job, BuildJob& b) {
  Result<BuildFileOptions> options = build_file_options(job.options);
  if (!options) {
    b.refused = b.where + ": " + options.error().message;
    return;
  }
  b.options = std::move(*options);
  b.options_key = json_text(output_options_json(job.options));
}

}  // namespace

std::string job_where(const std::string& jobs_path, int line) {
  return jobs_path + ":" + std::to_string(line);
}

Result<std::vector<Job>> read_batch_jobs(const std::string& jobs_path,
                                         const std::string& results_path) {
  Result<std::vector<Job>> jobs = read_jobs(jobs_path);
  if (!jobs) return jobs.error();
  std::vector<BuildJob*> builds;
  for (Job& job : *jobs) {
    job.build = job_files(job, job_where(jobs_path, job.line));
    builds.push_back(&job.build);
  }
  if (Status s = refuse_clashing_outputs(builds, {jobs_path, results_path}); !s) return s.error();
  for (Job& job : *jobs) {
    job.error = job.build.refused;
    if (job.error.empty()) set_build_options(job, job.build);
  }
  return jobs;
}

}  // namespace lightvol::cli
