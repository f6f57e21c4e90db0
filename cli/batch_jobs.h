// The jobs file of `lightvol batch` (docs/batch.md), read into jobs: each line's arguments parsed
// by build's own flag definitions, the outputs checked; what the library runs
// (pipeline/build_job.h).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <lightvol/core/result.h>
#include <lightvol/pipeline/build_job.h>

#include "build_flags.h"

namespace lightvol::cli {

// One job line (core/jobs_file.h), with build's flags parsed. A line that is not a job is still
// one: it fails with `error`.
struct Job {
  int line = 0;                 // 1-based line number in the jobs file
  std::size_t number = 0;       // 0-based among the jobs (lines that are not blank or comments)
  nlohmann::ordered_json id;    // the line's "id", or null
  nlohmann::ordered_json out;   // the line's "out" as written, or null
  BuildCommandOptions options;  // paths resolved against the jobs file's folder
  std::string error;            // why the line is not a job, with the file and line
  BuildJob build;               // what the library runs (refused: `error`, or a flag conflict)
};

// "<jobs file>:<line>", as messages name a job.
std::string job_where(const std::string& jobs_path, int line);

// Every job of the jobs file at `jobs_path`, in order (so that a job's number, and so its shard,
// is the same in every shard). A job whose out or report is an earlier job's output, an input of
// any job or the jobs file fails (Job::error); --results (`results_path`, or "") naming an input,
// the jobs file or a job's output is an Error, as is a jobs file that cannot be read.
Result<std::vector<Job>> read_batch_jobs(const std::string& jobs_path,
                                         const std::string& results_path);

}  // namespace lightvol::cli
