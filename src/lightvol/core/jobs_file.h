// Batch jobs files (docs/batch.md): JSON lines, one `build` job each, read and split into job
// lines here; `lightvol batch` then parses each line's `args` with build's own flags.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <lightvol/core/result.h>

namespace lightvol {

// The most bytes a jobs file may hold: about a million job lines of 250 bytes. A longer file (or
// one that never ends) is refused, naming it.
inline constexpr std::size_t kMaxJobsFileBytes = std::size_t{256} << 20;

// One job line of a jobs file. A line that is not a job is still one, with `error` set: it fails
// as a job, and the lines around it still run.
struct JobLine {
  int line = 0;                     // 1-based line number in the file
  std::size_t number = 0;           // 0-based among the job lines (not blank lines or comments)
  std::optional<std::string> id;    // "id", once the line's keys are known
  std::optional<std::string> out;   // "out" as written, once "light" and "out" are paths
  std::vector<std::string> inputs;  // "inputs": at least one path
  std::string light;                // "light": a path
  std::vector<std::string> args;    // "args": build's flags, as written
  std::string error;                // "<source>:<line>: <why>" when the line is not a job
};

// The job lines of `text`, the contents of the jobs file `source` (which names it in errors):
// lines end at '\n' (a '\r' before it is dropped); blank lines and lines whose first non-blank
// character is '#' are not jobs. Each other line is a JSON object with the keys "inputs" (a
// non-empty array of paths), "light" and "out" (paths), and optionally "id" (a string) and "args"
// (an array of strings); a line that is not (malformed JSON, another key, a key given twice,
// nesting deeper than 32 levels, a wrong type, a control character in a path or flag) is a
// JobLine whose `error` names the line and the key. A pure function of `text`: no file is read.
// An Error only for a text longer than kMaxJobsFileBytes.
Result<std::vector<JobLine>> parse_jobs_text(std::string_view text, const std::string& source);

// The bytes of the jobs file at `path`: a regular file (symlinks followed) of at most
// kMaxJobsFileBytes. A missing or unreadable file, a directory, a device or a pipe (`/dev/zero`,
// a FIFO: a jobs file is read whole before any job runs, and its folder is where relative paths
// start) and a longer file are Errors naming `path`.
Result<std::string> read_jobs_file(const std::string& path);

}  // namespace lightvol
