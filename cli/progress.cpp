#include "progress.h"

#include <unistd.h>

#include <cstdio>

namespace lightvol::cli {

Progress::Progress(bool quiet) : show_(!quiet && ::isatty(STDERR_FILENO)) {
  if (!show_) return;
  log_.on_begin = [](const std::string& step) {
    std::fprintf(stderr, "%s ... ", step.c_str());
    std::fflush(stderr);
  };
  log_.on_end = [](const StageRecord& r, const std::string& detail) {
    std::fprintf(stderr, "%.2f s%s%s\n", r.seconds, detail.empty() ? "" : "  ", detail.c_str());
  };
}

std::string size_text(int width, int height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

std::string human_bytes(unsigned long long bytes) {
  char buf[32];
  const double b = static_cast<double>(bytes);
  if (b >= 1024.0 * 1024 * 1024)
    std::snprintf(buf, sizeof buf, "%.2f GiB", b / (1024.0 * 1024 * 1024));
  else if (b >= 1024.0 * 1024)
    std::snprintf(buf, sizeof buf, "%.0f MiB", b / (1024.0 * 1024));
  else
    std::snprintf(buf, sizeof buf, "%.0f KiB", b / 1024.0);
  return buf;
}

}  // namespace lightvol::cli
