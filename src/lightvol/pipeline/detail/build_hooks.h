// What a batch driver (pipeline/build_job.cpp) adds to one build_volume_file run.
#pragma once

#include <functional>
#include <string>

#include <nlohmann/json.hpp>

#include <lightvol/core/limits.h>
#include <lightvol/core/result.h>
#include <lightvol/depth/shadow_maps.h>
#include <lightvol/pipeline/build_file.h>

namespace lightvol::detail {

struct BuildFileHooks {
  // Called once the light and maps are read: an Error fails the run with its message (batch: an
  // input no longer holds the bytes its content hash covers).
  std::function<Status()> after_read;
  // Called after after_read, before the volume is built, with the build's memory mode
  // (core/limits.h build_memory_bytes); may block (batch: until the build's memory fits under the
  // budget beside the jobs already running). Its time is BuildStepSeconds::wait.
  std::function<void(const ShadowMaps& maps, BuildMemory mode)> before_build;
  // Called with the built volume before it is checked (options.check; tests: a volume broken so
  // that it fails its checks, while its file is written).
  std::function<void(Mesh& volume)> before_check;
  // Keys added to the report (batch: the job's content hash).
  nlohmann::json extra_report = nlohmann::json::object();
  // Called with the volume's file once it is written (the temporary that becomes out_path when the
  // outputs are committed), before the report is made: keys added to the report (batch: the
  // volume's size and hash, which a rerun checks before it skips the job), or an Error that fails
  // the run with nothing written.
  std::function<Result<nlohmann::json>(const std::string& volume_file)> volume_written;
};

BuildFileResult build_volume_file(const BuildFileOptions& options, StageLog& log,
                                  const BuildFileHooks& hooks);

}  // namespace lightvol::detail
