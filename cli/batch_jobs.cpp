// The jobs file of `lightvol batch` (docs/batch.md) as build command lines: each line's arguments
// parsed by build's own flag definitions (build_flags.h), its paths resolved against the jobs
// file's folder, and the outputs of the run checked against each other and against its inputs.
#include "batch_jobs.h"

#include <algorithm>
#include <filesystem>
#include <string>
#include <unordered_map>
#include <vector>

#include <lightvol/core/jobs_file.h>
#include <lightvol/core/path.h>

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

// Every job of the jobs file at `jobs_path`, so that a job's number, and so its shard, is the same
// in every shard; an output named by an earlier job fails the later one, whichever shards they
// fall in. `written`: each output's identity, and its job's line.
Result<std::vector<Job>> read_jobs(const std::string& jobs_path,
                                   std::unordered_map<std::string, int>* written) {
  Result<std::string> text = read_jobs_file(jobs_path);
  if (!text) return text.error();
  Result<std::vector<JobLine>> lines = parse_jobs_text(*text, jobs_path);
  if (!lines) return lines.error();
  *text = std::string();
  const fs::path base = fs::path(jobs_path).parent_path();
  std::vector<Job> all;
  all.reserve(lines->size());
  for (const JobLine& line : *lines) {
    Job job = parse_job(line, job_where(jobs_path, line.line), base);
    if (job.error.empty()) {
      const std::string* const paths[2] = {&job.options.out_path, &job.options.report_path};
      std::string identity[2];
      for (int k = 0; k < 2 && job.error.empty(); ++k) {
        identity[k] = file_identity(*paths[k]);
        if (const auto earlier = written->find(identity[k]); earlier != written->end())
          job.error = job_where(jobs_path, line.line) + ": " + *paths[k] +
                      ": also an output of line " + std::to_string(earlier->second) +
                      "; give each job its own out (and report)";
      }
      if (job.error.empty())
        for (const std::string& id : identity) written->emplace(id, line.line);
    }
    all.push_back(std::move(job));
  }
  return all;
}

// The paths of `o` that name what a build reads.
BuildFileOptions paths_of(const BuildCommandOptions& o) {
  BuildFileOptions paths;
  paths.depth_paths = o.depth_paths;
  paths.light_path = o.light_path;
  paths.medium_path = o.medium_path;
  return paths;
}

// The library's job for `job`, which "<jobs file>:<line>" names.
BuildJob build_job(const Job& job, const std::string& where) {
  BuildJob b;
  b.where = where;
  b.refused = job.error;
  if (!job.error.empty()) return b;
  Result<BuildFileOptions> options = build_file_options(job.options);
  if (!options) {
    b.refused = where + ": " + options.error().message;
    return b;
  }
  b.options = std::move(*options);
  b.options_key = json_text(output_options_json(job.options));
  return b;
}

// No output of the run may be one of its inputs (compared by core/path.h file_identity: the same
// inode, or the same new path): a job whose out or report is read by any job, or is the jobs file,
// fails; --results naming an input, the jobs file or a job's output stops the batch, returning its
// message ("" when nothing clashes). `written`: each job output's identity and its job's line.
std::string check_outputs(const std::string& jobs_path, const std::string& results_path,
                          std::vector<Job>& all,
                          const std::unordered_map<std::string, int>& written) {
  std::unordered_map<std::string, std::string> read;  // identity: what reads it
  read.emplace(file_identity(jobs_path), "the jobs file");
  for (const Job& job : all)
    if (job.error.empty())
      for (const auto& [key, path] : build_input_files(paths_of(job.options)))
        read.emplace(file_identity(path), path + ", an input of line " + std::to_string(job.line) +
                                              " (key '" + key + "')");
  for (Job& job : all) {
    if (!job.error.empty()) continue;
    for (const std::string* out : {&job.options.out_path, &job.options.report_path})
      if (const auto input = read.find(file_identity(*out)); input != read.end()) {
        job.error = job_where(jobs_path, job.line) + ": " + *out + ": is also " + input->second +
                    "; an output may not replace an input";
        break;
      }
  }
  if (results_path.empty()) return {};
  const std::string results = file_identity(results_path);
  if (const auto input = read.find(results); input != read.end())
    return "--results " + results_path + ": is also " + input->second +
           "; an output may not replace an input";
  if (const auto output = written.find(results); output != written.end())
    return "--results " + results_path + ": is also an output of line " +
           std::to_string(output->second) + "; give the results their own file";
  return {};
}

}  // namespace

std::string job_where(const std::string& jobs_path, int line) {
  return jobs_path + ":" + std::to_string(line);
}

Result<std::vector<Job>> read_batch_jobs(const std::string& jobs_path,
                                         const std::string& results_path) {
  std::unordered_map<std::string, int> written;  // each output's identity, and its job's line
  Result<std::vector<Job>> jobs = read_jobs(jobs_path, &written);
  if (!jobs) return jobs.error();
  if (const std::string clash = check_outputs(jobs_path, results_path, *jobs, written);
      !clash.empty())
    return Error{clash};
  for (Job& job : *jobs) job.build = build_job(job, job_where(jobs_path, job.line));
  return jobs;
}

}  // namespace lightvol::cli
