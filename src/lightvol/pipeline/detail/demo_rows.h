// The demo's report rows (pipeline/demo.h), as its CPU steps (demo.cpp) and its GPU steps
// (gl_demo.cpp) both add them.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <lightvol/core/stages.h>
#include <lightvol/pipeline/demo.h>

namespace lightvol::detail {

// "1024x768".
inline std::string size_text(int width, int height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

// Ends the step `log` is timing and reports it as `row`, with its seconds.
inline void end_row(StageLog& log, std::vector<DemoRow>* rows, DemoRow row) {
  log.end();
  row.seconds = log.last_seconds();
  rows->push_back(std::move(row));
}

}  // namespace lightvol::detail
