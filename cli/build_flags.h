// The `lightvol build` command line: its flags, their definitions (which `batch` parses each job
// line's arguments with too), and the library options they make (pipeline/build_file.h).
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <lightvol/core/result.h>
#include <lightvol/pipeline/build_file.h>

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
// --report), with its value: what a batch job's content hash covers (BuildJob::options_key). Add
// a new flag here.
nlohmann::json output_options_json(const BuildCommandOptions& o);

// The library's options for `o`, or an Error naming the flags that do not go together (--draco
// without a .glb output, --max-error without --adaptive, ...).
Result<BuildFileOptions> build_file_options(const BuildCommandOptions& o);

}  // namespace lightvol::cli
