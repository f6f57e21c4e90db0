// One `lightvol build` run as a function: its options, the flags that set them, and the pipeline
// (light, maps, volume, check, outputs) returning what happened instead of printing it. `build`
// runs it once and prints; `batch` runs it once per job line, in threads.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <lightvol/core/limits.h>
#include <lightvol/depth/shadow_maps.h>

#include "progress.h"

namespace lightvol::cli {

struct BuildCommandOptions {
  std::vector<std::string> depth_paths;
  std::string light_path;
  std::string out_path;
  std::string channel;
  std::string space = "world";
  std::string report_path;
  std::string medium_path;  // --medium: recorded in a GLB's light node
  bool ascii = false;
  bool draco = false;
  int draco_bits = 16;
  bool quiet = false;
  bool json = false;
  bool adaptive = false;         // --adaptive
  double max_error = -1;         // --max-error, world units
  std::string refine = "error";  // --refine error|laplacian
  double threshold = -1;         // --threshold, for --refine laplacian
  std::string tessellation;      // --tessellation collapse|quadtree (default: collapse; laplacian:
                                 // quadtree)
  bool no_check = false;
};

// Declares build's arguments and flags on `cmd`, filling `o` when it parses: the one definition
// of the build command line, which `batch` also parses each job's arguments with.
void add_build_options(CLI::App& cmd, BuildCommandOptions& o);

// Every option that changes the bytes `build` writes (not the paths, --quiet, --json or
// --report), with its value: what a batch job's content hash covers. Add a new flag here.
nlohmann::json output_options_json(const BuildCommandOptions& o);

// What a caller adds to one build run.
struct BuildJobHooks {
  // Called once the light and maps are read, before the volume is built, with the build's memory
  // mode (core/limits.h build_memory_bytes); may block (batch: until the build's memory fits under
  // the budget beside the jobs already running).
  std::function<void(const ShadowMaps& maps, BuildMemory mode)> before_build;
  // Called once the light and maps are read, before before_build: an Error fails the run (exit 2)
  // with its message (batch: an input no longer holds the bytes its content hash covers).
  std::function<Status()> after_read;
  // Keys added to the report (batch: the job's content hash).
  nlohmann::json extra_report = nlohmann::json::object();
  // Called with the volume's file once it is written (the temporary that becomes --out when the
  // outputs are committed), before the report is made: keys added to the report (batch: the
  // volume's size and hash, which a rerun checks before it skips the job), or an Error that fails
  // the run with nothing written.
  std::function<Result<nlohmann::json>(const std::string& volume_file)> volume_written;
  // The light's and the medium's bytes, when the caller has read them (batch: the bytes its
  // content hash covers): parsed instead of reading the files again, so that a pipe is read once
  // and what is built is what was hashed.
  const std::string* light_text = nullptr;
  const std::string* medium_text = nullptr;
};

// What one build run did.
struct BuildJobResult {
  int exit_code = 0;  // 0 written, else exit_code(kind): 1 the volume fails its checks, 2 others
  ErrorKind kind = ErrorKind::bad_input;  // when exit_code != 0
  std::string error;  // the one-line message when exit_code != 0 (without "lightvol: ")
  std::vector<std::string> warnings;
  std::uint64_t vertices = 0, triangles = 0;
  double read_seconds = 0;   // the light, the maps, the medium
  double wait_seconds = 0;   // in before_build
  double build_seconds = 0;  // the volume
  double check_seconds = 0;  // the linear-time checks
  double write_seconds = 0;  // the outputs, committed together
  nlohmann::json report;     // the --report / --json report, when written
};

// Runs `build` with `o`: reads, builds, checks and writes the volume (and the --report file)
// atomically, or writes nothing. Prints nothing; `progress` times the steps (and shows them on a
// terminal unless quiet).
BuildJobResult run_build_job(const BuildCommandOptions& o, Progress& progress,
                             const BuildJobHooks& hooks = {});

}  // namespace lightvol::cli
