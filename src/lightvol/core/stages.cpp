#include <sys/resource.h>

#include <lightvol/core/check.h>
#include <lightvol/core/stages.h>

namespace lightvol {

std::uint64_t peak_memory_bytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<std::uint64_t>(usage.ru_maxrss) * 1024u;  // Linux reports kilobytes
}

void StageLog::begin(std::string name) {
  current_ = std::move(name);
  if (on_begin) on_begin(current_);
  start_ = std::chrono::steady_clock::now();
}

const StageRecord& StageLog::end(const std::string& detail) {
  LV_CHECK(!current_.empty());
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  stages_.push_back({std::move(current_), s, peak_memory_bytes()});
  current_.clear();
  if (on_end) on_end(stages_.back(), detail);
  return stages_.back();
}

double StageLog::total_seconds() const {
  double s = 0;
  for (const auto& st : stages_) s += st.seconds;
  return s;
}

}  // namespace lightvol
