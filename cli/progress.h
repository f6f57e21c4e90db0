// Timed progress lines on stderr: shown on a terminal, silent when piped or with --quiet. The
// steps are timed by a StageLog (core/stages.h), which the library's pipelines also time their
// steps in; this prints them.
#pragma once

#include <string>

#include <lightvol/core/stages.h>
#include <lightvol/core/text.h>  // thousands

namespace lightvol::cli {

class Progress {
 public:
  explicit Progress(bool quiet);
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  // Starts a step ("reading depth.exr") and its timer.
  void begin(const std::string& step) { log_.begin(step); }
  // Ends the current step, printing its time, and records it in the stage log.
  void end(const std::string& detail = "") { log_.end(detail); }
  // The log the steps are recorded in: what a library pipeline is given to time its steps.
  StageLog& log() { return log_; }
  const StageLog& log() const { return log_; }
  bool shown() const { return show_; }

 private:
  bool show_;
  StageLog log_;
};

// "1024x768".
std::string size_text(int width, int height);
// Formats bytes as "1.23 GiB", "512 MiB", ...
std::string human_bytes(unsigned long long bytes);

}  // namespace lightvol::cli
