// Timing and peak memory of pipeline stages, for progress lines and --report files.
#pragma once

#include <chrono>
#include <cstdint>
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

// A list of finished stages. begin() starts the clock for the next one; end() records it.
class StageLog {
 public:
  void begin(std::string name);
  const StageRecord& end();
  const std::vector<StageRecord>& stages() const { return stages_; }
  double total_seconds() const;

 private:
  std::vector<StageRecord> stages_;
  std::string current_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace lightvol
