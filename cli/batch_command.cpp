// lightvol batch: many `build` jobs from one JSON-lines file, run in threads of one process, one
// JSON line of result per job; --shard K/N runs one deterministic slice of them (docs/batch.md).
// The jobs file is read by the library (core/jobs_file.h), each line's arguments parsed here by
// build's own flag definitions, and the jobs run by the library (pipeline/build_job.h: content
// hashes, skipping, memory admission).
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include <lightvol/core/atomic_file.h>
#include <lightvol/pipeline/build_job.h>

#include "batch_jobs.h"
#include "commands.h"

namespace lightvol::cli {
namespace {
using ordered_json = nlohmann::ordered_json;

// The most jobs run at once: each holds up to two temporary files (the volume and its report),
// which the signal cleanup of core/atomic_file.h tracks in a table of fixed size.
constexpr int kMaxParallelJobs = 64;

struct BatchOptions {
  std::string jobs_path;
  int jobs = 0;       // --jobs; 0: one per core
  std::string shard;  // --shard K/N
  bool shard_given = false;
  std::string results_path;
  bool quiet = false;
};

struct Shard {
  long index = 0, count = 1;
};

// "K/N" with 0 <= K < N.
Result<Shard> parse_shard(const std::string& text) {
  const std::string usage = "--shard: expected K/N with 0 <= K < N (e.g. 0/4), got '" + text + "'";
  const std::size_t slash = text.find('/');
  if (slash == std::string::npos) return Error{usage};
  auto number = [](const std::string& digits, long* value) {
    if (digits.empty() || digits.size() > 9 ||
        !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
      return false;
    *value = std::stol(digits);
    return true;
  };
  Shard s;
  if (!number(text.substr(0, slash), &s.index) || !number(text.substr(slash + 1), &s.count) ||
      s.count < 1 || s.index >= s.count)
    return Error{usage};
  return s;
}

std::string result_line(const Job& job, const BuildJobResult& r) {
  const bool failed = r.status == JobStatus::failed;
  const BuildStepSeconds& s = r.seconds;
  ordered_json line = {
      {"line", job.line},
      {"id", job.id},
      {"status", r.status == JobStatus::ok        ? "ok"
                 : r.status == JobStatus::skipped ? "skipped"
                                                  : "failed"},
      {"out", job.out},
      {"vertices", failed ? ordered_json(nullptr) : ordered_json(r.vertices)},
      {"triangles", failed ? ordered_json(nullptr) : ordered_json(r.triangles)},
      {"seconds",
       {{"hash", r.hash_seconds},
        {"read", s.read},
        {"wait", s.wait},
        {"build", s.build},
        {"check", s.check},
        {"write", s.write}}},
      {"error", failed ? ordered_json(with_flags(r.error.message)) : ordered_json(nullptr)}};
  return json_text(line);
}

int run_batch(const BatchOptions& opts) {
  Result<Shard> shard = !opts.shard_given ? Result<Shard>(Shard{}) : parse_shard(opts.shard);
  if (!shard) return fail(shard.error().message);
  Result<std::vector<Job>> jobs = read_batch_jobs(opts.jobs_path, opts.results_path);
  if (!jobs) return fail(jobs.error().message);
  const std::vector<Job>& all = *jobs;

  std::vector<const Job*> mine;  // this shard's: job i belongs to shard i mod N
  std::vector<const BuildJob*> run;
  for (const Job& job : all)
    if (static_cast<long>(job.number % static_cast<std::size_t>(shard->count)) == shard->index) {
      mine.push_back(&job);
      run.push_back(&job.build);
    }

  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const int workers = static_cast<int>(
      std::min<std::size_t>(std::min(opts.jobs > 0 ? opts.jobs : cores, kMaxParallelJobs),
                            std::max<std::size_t>(1, mine.size())));
  const bool tty = ::isatty(STDERR_FILENO) != 0;
  const auto started = std::chrono::steady_clock::now();
  std::vector<std::string> lines;  // for --results
  std::size_t done = 0, ok = 0, skipped = 0, failed = 0;
  int exit_code = 0;
  const auto finished = [&](std::size_t, const BuildJobResult& r) {
    ++done;
    if (r.status == JobStatus::ok) ++ok;
    if (r.status == JobStatus::skipped) ++skipped;
    if (r.status == JobStatus::failed) {
      ++failed;
      exit_code = std::max(exit_code, cli::exit_code(r.error.kind));
      if (!opts.quiet)
        std::fprintf(stderr, "%slightvol: %s\n", tty ? "\r\033[K" : "",
                     printable(with_flags(r.error.message)).c_str());
    }
    if (!opts.quiet && tty)
      std::fprintf(stderr, "\r\033[Kbatch: %zu/%zu done, %zu failed", done, mine.size(), failed);
  };
  // Result lines in job order, each as soon as it and every job before it are done.
  const auto in_order = [&](std::size_t i, const BuildJobResult& r) {
    const std::string line = result_line(*mine[i], r);
    if (!opts.results_path.empty()) return lines.push_back(line);
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
  };
  run_build_jobs(run, workers, finished, in_order);

  if (!opts.results_path.empty()) {
    std::string all_lines;
    for (const std::string& line : lines) all_lines += line + "\n";
    if (Status s = write_bytes_atomically(opts.results_path, all_lines); !s)
      return fail(s.error().message);
  }
  if (!opts.quiet) {
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    const std::string which = !opts.shard_given
                                  ? std::to_string(mine.size()) + " jobs"
                                  : "shard " + opts.shard + ": " + std::to_string(mine.size()) +
                                        " of " + std::to_string(all.size()) + " jobs";
    std::fprintf(stderr, "%sbatch: %s: %zu ok, %zu skipped, %zu failed, %.2f s\n",
                 tty ? "\r\033[K" : "", which.c_str(), ok, skipped, failed, seconds);
  }
  return exit_code;
}

}  // namespace

void add_batch_command(CLI::App& app, Runner* run) {
  auto o = std::make_shared<BatchOptions>();
  CLI::App* cmd = app.add_subcommand(
      "batch", "Run many builds from a JSON-lines file, in parallel, one result line per job.");
  cmd->footer(
      "Each line of JOBS.jsonl is one build: {\"id\": \"a\", \"inputs\": [\"a.exr\"], \"light\": "
      "\"l.json\",\n"
      "\"out\": \"a.ply\", \"args\": [\"--adaptive\", \"--max-error\", \"0.01\"]}; args are "
      "build's flags.\n"
      "Paths are relative to the jobs file's folder. Blank lines and lines starting with # are "
      "skipped.\n"
      "A job whose output and report (<out>.report.json) exist with the same content hash, and "
      "whose\noutput still has the size and hash its report recorded, is skipped.\n"
      "Results: one JSON line per job on stdout, in job order. Exit 0 when every job is ok or "
      "skipped,\n"
      "1 when a volume failed its checks, 2 when a job had bad input. See docs/batch.md.");
  cmd->add_option("jobfile", o->jobs_path, "The jobs (JOBS.jsonl): one JSON object per line")
      ->required();
  cmd->add_option("--jobs,-j", o->jobs, "Jobs run at once (default: one per core; at most 64)")
      ->check(decimal_integer())
      ->check(CLI::Range(1, kMaxParallelJobs));
  cmd->add_option("--shard", o->shard,
                  "Run the K-th of N slices, K/N (0 <= K < N): the jobs i with i mod N = K");
  cmd->add_option(
      "--results", o->results_path,
      "Write the result lines to this file (atomically, at the end) instead of stdout (- for "
      "stdout, at the end)");
  cmd->add_flag("--quiet,-q", o->quiet, "No progress, failures or summary on stderr");
  cmd->callback([o, run, cmd] {
    o->shard_given = cmd->count("--shard") > 0;
    *run = [o] { return run_batch(*o); };
  });
}

}  // namespace lightvol::cli
