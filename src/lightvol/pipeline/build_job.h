// Many volume files, as a batch driver makes them (`lightvol batch`, docs/batch.md): each job one
// build_volume_file run, skipped when the files it would write are already those of the same
// inputs (a content hash of everything it reads, recorded in its report), admitted only when its
// build's memory fits under the budget beside the jobs already running.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include <lightvol/core/result.h>
#include <lightvol/pipeline/build_file.h>

namespace lightvol {

struct BuildJob {
  // The build; report_path must be set: the report records the content hash that lets a rerun
  // skip the job.
  BuildFileOptions options;
  // Every option that changes the bytes written, as the caller names them (text; part of the
  // content hash, so that a job whose options changed is built again).
  std::string options_key;
  std::string where;  // begins the job's errors ("jobs.jsonl:3")
  int line = 0;       // the job's line in its jobs file, as other jobs' messages name it
  // When not empty, the job is not run: it fails with this message (a jobs-file line that is not a
  // job). Not prefixed with `where`.
  std::string refused;
};

// The files a build reads, in order, each with the job-line key that names it (docs/batch.md): its
// depth inputs ("inputs"; {face} expanded to six, depth_input_files), the light ("light"), the
// medium ("args: --medium").
std::vector<std::pair<std::string, std::string>> build_input_files(const BuildFileOptions& options);

// The files a batch names besides its jobs' own: the jobs file, and the file its results go to
// ("" for none).
struct BatchFiles {
  std::string jobs_path;
  std::string results_path;
};

// Checks that no output of a batch replaces another or an input (compared by core/path.h
// file_identity: the same inode, or the same new path), in job order: a job whose out_path or
// report_path is an output of an earlier job is refused (BuildJob::refused, naming that job's
// line); then a job whose out_path or report_path is a file any job reads (build_input_files) or
// the jobs file is refused. Jobs refused already take no part (their files are neither outputs
// nor inputs). An Error when BatchFiles::results_path is the jobs file, an input or a job's
// output. Call before running the jobs: only options' paths are read.
Status refuse_clashing_outputs(const std::vector<BuildJob*>& jobs, const BatchFiles& files);

enum class JobStatus { ok, skipped, failed };

struct BuildJobResult {
  JobStatus status = JobStatus::failed;
  Error error;  // when failed: the message, beginning with the job's `where` (unless refused)
  std::uint64_t vertices = 0, triangles = 0;  // of the volume written, or recorded (skipped)
  double hash_seconds = 0;                    // the content hash of the inputs
  BuildStepSeconds seconds;                   // the build's steps (zero when skipped)
};

// Admission: a job waits, after reading its maps, until the memory its build needs fits under the
// budget beside the builds already running; the first one always runs.
class MemoryGate {
 public:
  explicit MemoryGate(std::uint64_t budget) : budget_(budget) {}
  void acquire(std::uint64_t bytes);
  void release(std::uint64_t bytes);

 private:
  std::mutex mutex_;
  std::condition_variable fits_;
  std::uint64_t budget_;
  std::uint64_t held_ = 0;
};

// Runs one job: its content hash ("xxh3-128:<32 hex digits>", of every file it reads, its
// options_key and lightvol's version); skipped when its output and report exist, the report
// records that hash, and the output still has the size and hash the report recorded (output_bytes,
// output_hash); else built (build_volume_file), with the hash and the output's size and hash in
// its report. An input whose bytes change while the job reads it fails the job, nothing written.
// Prints nothing. Exceptions (out of memory) become failures.
BuildJobResult run_build_job(const BuildJob& job, MemoryGate& gate);

// Runs `jobs` on `workers` threads (at least 1), sharing one MemoryGate of memory_budget(). For
// each job, under one lock (one call at a time): `finished(i, result)` as it finishes, in any
// order; then `in_order(i, result)` for every job whose result and all before it are known, in
// job order, as soon as they are.
void run_build_jobs(const std::vector<const BuildJob*>& jobs, int workers,
                    const std::function<void(std::size_t, const BuildJobResult&)>& finished,
                    const std::function<void(std::size_t, const BuildJobResult&)>& in_order);

}  // namespace lightvol
