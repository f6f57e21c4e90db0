// Timing and peak memory of pipeline stages, for progress lines and --report files.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace lightvol {

// Peak resident memory of this process so far, in bytes (getrusage).
std::uint64_t peak_memory_bytes();

struct StageRecord {
  std::string name;
  double seconds = 0;
  std::uint64_t peak_memory_bytes = 0;  // process peak at the end of the stage
};

// A list of finished stages. begin() starts the clock for the next one; end() records it. The
// library's pipelines (pipeline/) time their steps in the caller's log; a caller that shows them
// (a command line's progress lines) sets the listeners, called as each stage begins and ends.
class StageLog {
 public:
  std::function<void(const std::string& name)> on_begin;
  // `detail`: what the stage made, for a progress line ("48x48 x 6", "1,234 triangles").
  std::function<void(const StageRecord& stage, const std::string& detail)> on_end;

  void begin(std::string name);
  const StageRecord& end(const std::string& detail = "");
  // The seconds of the stage that ended last (0 before any has).
  double last_seconds() const { return stages_.empty() ? 0 : stages_.back().seconds; }
  const std::vector<StageRecord>& stages() const { return stages_; }
  double total_seconds() const;

 private:
  std::vector<StageRecord> stages_;
  std::string current_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace lightvol
