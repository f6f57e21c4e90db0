#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include <nlohmann/json.hpp>

#include <lightvol/core/detail/json_keys.h>
#include <lightvol/core/jobs_file.h>
#include <lightvol/core/path.h>

namespace lightvol {
namespace {

using nlohmann::json;

// One job line, parsed; `where` is "<source>:<line>".
JobLine parse_job_line(std::string_view text, const std::string& where) {
  JobLine job;
  auto bad = [&](const std::string& why) {
    job.error = where + ": " + why;
    return job;
  };
  const json::parser_callback_t check = strict_json_check([](const std::string& key) {
    return "key '" + key + "': given twice (a job gives each key once)";
  });
  json j;
  try {
    j = json::parse(text.begin(), text.end(), check);
  } catch (const JsonRefused& r) {
    return bad(r.why);
  } catch (const json::parse_error& e) {
    return bad("not valid JSON (at byte " + std::to_string(e.byte) + ")");
  } catch (const json::exception&) {  // out_of_range: a number like 1e99999
    return bad("not valid JSON (a number out of range)");
  }
  if (!j.is_object()) return bad("a job is a JSON object, e.g. {\"inputs\": [\"a.exr\"], ...}");
  for (const auto& [key, value] : j.items())
    if (key != "id" && key != "inputs" && key != "light" && key != "out" && key != "args")
      return bad("key '" + key + "': unknown (a job has id, inputs, light, out, args)");
  if (j.contains("id")) {
    if (!j["id"].is_string()) return bad("key 'id': expected a string");
    job.id = j["id"].get<std::string>();
  }
  auto strings = [&](const char* key, bool required, std::vector<std::string>* list) {
    if (!j.contains(key)) return !required;
    const json& v = j[key];
    if (!v.is_array() || (required && v.empty())) return false;
    for (const json& s : v) {
      if (!s.is_string()) return false;
      list->push_back(s.get<std::string>());
    }
    return true;
  };
  if (!strings("inputs", true, &job.inputs))
    return bad("key 'inputs': expected a non-empty array of paths");
  for (const char* key : {"light", "out"})
    if (!j.contains(key) || !j[key].is_string() || j[key].get<std::string>().empty())
      return bad(std::string("key '") + key + "': expected a path");
  job.light = j["light"].get<std::string>();
  job.out = j["out"].get<std::string>();
  if (!strings("args", false, &job.args)) return bad("key 'args': expected an array of strings");
  // A NUL ends a path early ("v\u0000.ply" is "v"), a line break splits messages: no path or
  // flag may hold a control character.
  const std::pair<const char*, std::vector<std::string>> fields[] = {
      {"inputs", job.inputs}, {"light", {job.light}}, {"out", {*job.out}}, {"args", job.args}};
  for (const auto& [key, values] : fields)
    for (const std::string& value : values)
      if (const std::string at = control_character_in(value); !at.empty())
        return bad(std::string("key '") + key + "': " + at + "; paths and flags may not hold one");
  return job;
}

}  // namespace

Result<std::vector<JobLine>> parse_jobs_text(std::string_view text, const std::string& source) {
  if (text.size() > kMaxJobsFileBytes)
    return Error{source + ": is larger than 256 MiB, the most a jobs file may hold; split it"};
  std::vector<JobLine> jobs;
  int line = 0;
  for (std::size_t start = 0; start < text.size();) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view content = text.substr(start, end - start);
    start = end + 1;
    ++line;
    if (!content.empty() && content.back() == '\r') content.remove_suffix(1);
    const std::size_t first = content.find_first_not_of(" \t");
    if (first == std::string_view::npos || content[first] == '#') continue;  // blank, a comment
    JobLine job = parse_job_line(content, source + ":" + std::to_string(line));
    job.line = line;
    job.number = jobs.size();
    jobs.push_back(std::move(job));
  }
  return jobs;
}

Result<std::string> read_jobs_file(const std::string& path) {
  const std::string cannot_open = path + ": cannot open the jobs file";
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return Error{cannot_open + ": " + std::strerror(errno)};
  const std::string not_regular =
      path + ": is not a regular file (a device or a pipe); a jobs file is read from a file";
  if (S_ISDIR(st.st_mode)) return Error{path + ": is a directory, not a jobs file"};
  if (!S_ISREG(st.st_mode)) return Error{not_regular};
  // Opened without blocking (a path swapped for a FIFO meanwhile would never open) and checked
  // again on the descriptor.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) return Error{cannot_open + ": " + std::strerror(errno)};
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) return Error{not_regular};
  const Error too_long{path + ": is larger than 256 MiB, the most a jobs file may hold; split it"};
  if (static_cast<std::uint64_t>(st.st_size) > kMaxJobsFileBytes) return too_long;
  std::string text;
  char buffer[1 << 16];
  for (;;) {  // to its end, which may have moved: never more than the limit
    const ssize_t got = ::read(fd, buffer, sizeof buffer);
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) return Error{path + ": cannot read the jobs file: " + std::strerror(errno)};
    if (got == 0) break;
    text.append(buffer, static_cast<std::size_t>(got));
    if (text.size() > kMaxJobsFileBytes) return too_long;
  }
  return text;
}

}  // namespace lightvol
