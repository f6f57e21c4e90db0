// Fuzz target: batch jobs files (core/jobs_file.h parse_jobs_text). Any text gives job lines in
// order, each a job or a line whose error names the file and the line; a job has its inputs, light
// and out, and no control character in any of them or in its args.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include <lightvol/core/check.h>
#include <lightvol/core/jobs_file.h>
#include <lightvol/core/path.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const lightvol::Result<std::vector<lightvol::JobLine>> jobs =
      lightvol::parse_jobs_text(text, "fuzz.jsonl");
  LV_CHECK(jobs.ok());  // the text is far below the size limit
  int previous = 0;
  for (std::size_t i = 0; i < jobs->size(); ++i) {
    const lightvol::JobLine& job = (*jobs)[i];
    LV_CHECK_EQ(job.number, i);
    LV_CHECK(job.line > previous);
    previous = job.line;
    if (!job.error.empty()) {
      const std::string where = "fuzz.jsonl:" + std::to_string(job.line) + ": ";
      LV_CHECK(job.error.rfind(where, 0) == 0);
      continue;
    }
    LV_CHECK(!job.inputs.empty() && !job.light.empty() && job.out && !job.out->empty());
    for (const std::string& s : job.inputs) LV_CHECK(lightvol::control_character_in(s).empty());
    for (const std::string& s : job.args) LV_CHECK(lightvol::control_character_in(s).empty());
    LV_CHECK(lightvol::control_character_in(job.light).empty());
    LV_CHECK(lightvol::control_character_in(*job.out).empty());
  }
  return 0;
}
