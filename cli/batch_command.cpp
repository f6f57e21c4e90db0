// lightvol batch: many `build` jobs from one JSON-lines file, run in threads of one process, one
// JSON line of result per job; --shard K/N runs one deterministic slice of them (docs/batch.md).
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include <nlohmann/json.hpp>

#include <lightvol/core/atomic_file.h>
#include <lightvol/core/jobs_file.h>
#include <lightvol/core/limits.h>
#include <lightvol/core/path.h>
#include <lightvol/core/text_file.h>
#include <lightvol/depth/cube_faces.h>

#include "build_job.h"
#include "commands.h"
#include "progress.h"

namespace lightvol::cli {
namespace {
namespace fs = std::filesystem;
using ordered_json = nlohmann::ordered_json;

// The most jobs run at once: each holds up to two temporary files (the volume and its report),
// which the signal cleanup of core/atomic_file.h tracks in a table of fixed size.
constexpr int kMaxParallelJobs = 64;

struct BatchOptions {
  std::string jobs_path;
  int jobs = 0;       // --jobs; 0: one per core
  std::string shard;  // --shard K/N
  bool shard_given = false;
  std::string results_path;
  bool quiet = false;
};

struct Shard {
  long index = 0, count = 1;
};

// "K/N" with 0 <= K < N.
Result<Shard> parse_shard(const std::string& text) {
  const std::string usage = "--shard: expected K/N with 0 <= K < N (e.g. 0/4), got '" + text + "'";
  const std::size_t slash = text.find('/');
  if (slash == std::string::npos) return Error{usage};
  auto number = [](const std::string& digits, long* value) {
    if (digits.empty() || digits.size() > 9 ||
        !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
      return false;
    *value = std::stol(digits);
    return true;
  };
  Shard s;
  if (!number(text.substr(0, slash), &s.index) || !number(text.substr(slash + 1), &s.count) ||
      s.count < 1 || s.index >= s.count)
    return Error{usage};
  return s;
}

// One job line (core/jobs_file.h), with build's flags parsed. A line that is not a job is still
// one: it fails with `error`.
struct Job {
  int line = 0;                 // 1-based line number in the jobs file
  std::size_t number = 0;       // 0-based among the jobs (lines that are not blank or comments)
  ordered_json id;              // the line's "id", or null
  ordered_json out;             // the line's "out" as written, or null
  BuildCommandOptions options;  // paths resolved against the jobs file's folder
  std::string error;            // why the line is not a job, with the file and line
};

std::string resolve(const fs::path& base, const std::string& path) {
  if (path.empty() || fs::path(path).is_absolute() || base.empty()) return path;
  return (base / path).string();
}

// A flag of `app` that needs a value, given last in `args` with none: batch's own "--" (which
// ends the flags of a job's line) would be its value (["--report"] used to write a file named
// "--"). Also any option that took a "--" as its value once parsed. "" when there is none.
std::string flag_without_value(const CLI::App& app, const std::vector<std::string>& args) {
  if (!args.empty()) {
    const std::string& last = args.back();
    if (last.size() > 1 && last[0] == '-' && last != "--" && last.find('=') == std::string::npos)
      if (const CLI::Option* option = app.get_option_no_throw(last);
          option && option->get_items_expected_min() > 0)
        return last;
  }
  for (const CLI::Option* option : app.get_options())
    for (const std::string& value : option->results())
      if (value == "--") return option->get_name();
  return "";
}

// A job file's path as messages name it.
std::string job_where(const std::string& jobs_path, int line) {
  return jobs_path + ":" + std::to_string(line);
}

// A job line's `args` parsed by build's own option definitions, its paths resolved against
// `base`; `where` ("<jobs file>:<line>") begins its errors.
Job parse_job(const JobLine& line, const std::string& where, const fs::path& base) {
  Job job;
  job.line = line.line;
  job.number = line.number;
  if (line.id) job.id = *line.id;
  if (line.out) job.out = *line.out;
  job.error = line.error;
  if (!job.error.empty()) return job;
  auto bad = [&](const std::string& why) {
    job.error = where + ": " + why;
    return job;
  };
  // build's command line: the flags first, then "--" and the inputs (a path may start with '-').
  std::vector<std::string> argv = {"--light", line.light, "--out", *line.out};
  argv.insert(argv.end(), line.args.begin(), line.args.end());
  argv.push_back("--");
  argv.insert(argv.end(), line.inputs.begin(), line.inputs.end());
  std::reverse(argv.begin(), argv.end());  // CLI11 takes them last first
  CLI::App build{"build"};
  build.name("build");
  build.set_help_flag();
  BuildCommandOptions& o = job.options;
  add_build_options(build, o);
  build.allow_extras();  // an unknown flag is named below
  if (const std::string flag = flag_without_value(build, line.args); !flag.empty())
    return bad("key 'args': " + flag + ": needs a value, and none follows it");
  try {
    build.parse(argv);
  } catch (const CLI::ParseError& e) {
    return bad("key 'args': " + std::string(e.what()));
  }
  if (const std::string flag = flag_without_value(build, {}); !flag.empty())
    return bad("key 'args': " + flag + ": needs a value, and none follows it");
  for (const std::string& extra : build.remaining())
    if (extra != "--")
      return bad("key 'args': " + extra + ": not a flag of build (see 'lightvol build --help')");
  if (o.json) return bad("key 'args': --json: not in a batch (each job's result is a line)");
  if (o.report_path == "-")
    return bad(
        "key 'args': --report -: a job's report is a file (batch reads it back to skip "
        "the job when nothing changed)");
  o.quiet = true;
  for (std::string& p : o.depth_paths) p = resolve(base, p);
  o.light_path = resolve(base, o.light_path);
  o.out_path = resolve(base, o.out_path);
  o.medium_path = resolve(base, o.medium_path);
  // Every job writes a report: it holds the content hash that makes a rerun skip the job.
  o.report_path =
      o.report_path.empty() ? o.out_path + ".report.json" : resolve(base, o.report_path);
  return job;
}

// Every job of the jobs file at `jobs_path`, so that a job's number, and so its shard, is the same
// in every shard; an output named by an earlier job fails the later one, whichever shards they
// fall in. `written`: each output's identity, and its job's line.
Result<std::vector<Job>> read_jobs(const std::string& jobs_path,
                                   std::unordered_map<std::string, int>* written) {
  Result<std::string> text = read_jobs_file(jobs_path);
  if (!text) return text.error();
  Result<std::vector<JobLine>> lines = parse_jobs_text(*text, jobs_path);
  if (!lines) return lines.error();
  *text = std::string();
  const fs::path base = fs::path(jobs_path).parent_path();
  std::vector<Job> all;
  all.reserve(lines->size());
  for (const JobLine& line : *lines) {
    Job job = parse_job(line, job_where(jobs_path, line.line), base);
    if (job.error.empty()) {
      const std::string* const paths[2] = {&job.options.out_path, &job.options.report_path};
      std::string identity[2];
      for (int k = 0; k < 2 && job.error.empty(); ++k) {
        identity[k] = file_identity(*paths[k]);
        if (const auto earlier = written->find(identity[k]); earlier != written->end())
          job.error = job_where(jobs_path, line.line) + ": " + *paths[k] +
                      ": also an output of line " + std::to_string(earlier->second) +
                      "; give each job its own out (and report)";
      }
      if (job.error.empty())
        for (const std::string& id : identity) written->emplace(id, line.line);
    }
    all.push_back(std::move(job));
  }
  return all;
}

// The files a job reads, in order, each with what names it in the job line: the depth inputs
// ({face} expanded to six), the light, the medium.
std::vector<std::pair<std::string, std::string>> input_files(const BuildCommandOptions& o) {
  std::vector<std::pair<std::string, std::string>> files;
  for (const std::string& p : o.depth_paths) {
    if (p.find("{face}") == std::string::npos) {
      files.emplace_back("inputs", p);
      continue;
    }
    for (int face = 0; face < kOmniFaces; ++face)
      files.emplace_back("inputs", expand_face_pattern(p, face));
  }
  files.emplace_back("light", o.light_path);
  if (!o.medium_path.empty()) files.emplace_back("args: --medium", o.medium_path);
  return files;
}

// What an image file was when its bytes were hashed: its inode, size and times as the descriptor
// saw them before the reading (any write since changes a time), and the digest of its bytes.
struct HashedFile {
  std::string key, path;
  struct stat seen {};
  XXH128_hash_t digest{};
};

// What a job read to take its content hash: the light's and the medium's bytes, kept for the build
// to parse (a pipe has no second reading, and the build is of what was hashed); and each image,
// which the build reads again (in lightvol-image), checked against what was hashed once it has.
struct JobReads {
  std::string light, medium;
  std::vector<HashedFile> images;
};

// One XXH3-128 state.
struct Hasher {
  std::unique_ptr<XXH3_state_t, decltype(&XXH3_freeState)> state{XXH3_createState(),
                                                                 &XXH3_freeState};
  Hasher() {
    if (!state || XXH3_128bits_reset(state.get()) != XXH_OK) throw std::bad_alloc();
  }
  void add(const void* bytes, std::size_t n) { XXH3_128bits_update(state.get(), bytes, n); }
  XXH128_hash_t digest() const { return XXH3_128bits_digest(state.get()); }
};

// "xxh3-128:<32 hex digits>".
std::string hex_digest(XXH128_hash_t digest) {
  XXH128_canonical_t canonical;
  XXH128_canonicalFromHash(&canonical, digest);
  std::string hex = "xxh3-128:";
  for (unsigned char byte : canonical.digest) {
    static constexpr char kHex[] = "0123456789abcdef";
    hex += kHex[byte >> 4];
    hex += kHex[byte & 15];
  }
  return hex;
}

// Feeds the regular file at `path` to `add` a chunk at a time, refusing what `build` refuses
// before it opens an image: a missing file, a directory, a device or a pipe (`/dev/zero` would
// never end, a FIFO without a writer would never open). Opened without blocking and checked
// again on the descriptor, so a path swapped for a FIFO meanwhile is refused too; at most the
// size the descriptor had is read. `seen`: the descriptor's stat before the reading.
Status hash_image_file(const std::string& key, const std::string& path,
                       const std::function<void(const char*, std::size_t)>& add,
                       struct stat* seen = nullptr) {
  const std::string where = "key '" + key + "': " + path + ": ";
  const std::string not_regular =
      "is not a regular file (a device or a pipe); images are read "
      "from files";
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status)) return Error{where + "cannot open: No such file or directory"};
  if (fs::is_directory(status)) return Error{where + "is a directory, not an image"};
  if (!fs::is_regular_file(status)) return Error{where + not_regular};
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) return Error{where + "cannot open: " + std::strerror(errno)};
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) return Error{where + not_regular};
  if (seen) *seen = st;
  std::vector<char> chunk(1 << 20);
  for (auto left = static_cast<std::uint64_t>(st.st_size); left > 0;) {
    const ssize_t got = ::read(
        fd, chunk.data(), static_cast<std::size_t>(std::min<std::uint64_t>(left, chunk.size())));
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) return Error{where + "cannot read: " + std::strerror(errno)};
    if (got == 0) break;  // shorter than it was: hashed as it is
    add(chunk.data(), static_cast<std::size_t>(got));
    left -= static_cast<std::uint64_t>(got);
  }
  return {};
}

// The job's content hash, "xxh3-128:<32 hex digits>": of the bytes of every file it reads (each
// with its length), the options that change the output, and the lightvol version. What was read
// is kept in `reads`.
Result<std::string> content_hash(const BuildCommandOptions& o, JobReads* reads) {
  Hasher job;
  auto add = [&](const std::string& bytes) {
    const std::uint64_t size = bytes.size();
    job.add(&size, sizeof size);
    job.add(bytes.data(), bytes.size());
  };
  add(std::string("lightvol ") + kVersion);
  add(json_text(output_options_json(o)));
  for (const auto& [key, path] : input_files(o)) {
    std::uint64_t size = 0;
    const std::uint64_t marker = ~std::uint64_t{0};  // a file, then its length after its bytes
    job.add(&marker, sizeof marker);
    if (key == "inputs") {
      Hasher file;
      HashedFile hashed{key, path};
      const Status read = hash_image_file(
          key, path,
          [&](const char* bytes, std::size_t n) {
            job.add(bytes, n);
            file.add(bytes, n);
            size += n;
          },
          &hashed.seen);
      if (!read) return read.error();
      hashed.digest = file.digest();
      reads->images.push_back(std::move(hashed));
    } else {
      const bool light = key == "light";
      Result<std::string> text =
          read_text_file(path, light ? "light description" : "medium description");
      if (!text) return Error{"key '" + key + "': " + text.error().message};
      job.add(text->data(), text->size());
      size = text->size();
      (light ? reads->light : reads->medium) = std::move(*text);
    }
    job.add(&size, sizeof size);
  }
  return hex_digest(job.digest());
}

bool same_file_state(const struct stat& a, const struct stat& b) {
  return a.st_dev == b.st_dev && a.st_ino == b.st_ino && a.st_size == b.st_size &&
         a.st_mtim.tv_sec == b.st_mtim.tv_sec && a.st_mtim.tv_nsec == b.st_mtim.tv_nsec &&
         a.st_ctim.tv_sec == b.st_ctim.tv_sec && a.st_ctim.tv_nsec == b.st_ctim.tv_nsec;
}

// After the build has read the images (lightvol-image opens them by path, apart from the hash):
// each must still be the file that was hashed, unchanged (its inode, size and times) and with the
// same bytes; else the volume may be of other bytes than the report's hash covers, and the job
// fails without writing anything.
Status images_unchanged(const JobReads& reads) {
  for (const HashedFile& image : reads.images) {
    Hasher again;
    struct stat now {};
    const Status read = hash_image_file(
        image.key, image.path, [&](const char* bytes, std::size_t n) { again.add(bytes, n); },
        &now);
    if (!read || !same_file_state(image.seen, now) || !XXH128_isEqual(again.digest(), image.digest))
      return Error{"key '" + image.key + "': " + image.path +
                   ": changed while the job read it (after its content hash was taken); nothing "
                   "written, run the batch again"};
  }
  return {};
}

// The size and the hash of the volume a job wrote, for its report: a rerun skips the job only if
// the output still has them.
Result<nlohmann::json> output_keys(const std::string& file) {
  Hasher bytes;
  std::uint64_t size = 0;
  const Status read = hash_image_file("out", file, [&](const char* data, std::size_t n) {
    bytes.add(data, n);
    size += n;
  });
  if (!read) return read.error();
  return nlohmann::json{{"output_bytes", size}, {"output_hash", hex_digest(bytes.digest())}};
}

// What a skipped job's result line says: the counts its report recorded.
struct Finished {
  std::uint64_t vertices = 0, triangles = 0;
};

// The counts of an earlier run, when its report vouches for this job as the files are now: the
// output and its report are regular files; the report is a JSON object whose job_hash is `hash`,
// whose vertices and triangles are counts (integers >= 0), and whose output_bytes and output_hash
// are the output's size and hash now. Anything else (a missing, truncated or replaced output, a
// report hand-edited or cut) is no vouching: the job runs again and writes both anew.
std::optional<Finished> finished_job(const BuildCommandOptions& o, const std::string& hash) {
  std::error_code ec;
  if (!fs::is_regular_file(o.out_path, ec) || !fs::is_regular_file(o.report_path, ec)) return {};
  const Result<std::string> text = read_text_file(o.report_path, "report");
  if (!text) return {};
  const nlohmann::json report = nlohmann::json::parse(*text, nullptr, false);
  if (!report.is_object()) return {};
  const auto string = [&](const char* key) {
    const auto it = report.find(key);
    return it != report.end() && it->is_string() ? it->get<std::string>() : std::string();
  };
  const auto count = [&](const char* key) -> std::optional<std::uint64_t> {
    const auto it = report.find(key);
    if (it == report.end() || !it->is_number_unsigned()) return {};
    return it->get<std::uint64_t>();
  };
  const std::optional<std::uint64_t> vertices = count("vertices"), triangles = count("triangles"),
                                     bytes = count("output_bytes");
  if (string("job_hash") != hash || !vertices || !triangles || !bytes) return {};
  const std::uintmax_t size = fs::file_size(o.out_path, ec);
  if (ec || size != *bytes) return {};
  const Result<nlohmann::json> now = output_keys(o.out_path);
  if (!now || (*now)["output_bytes"] != *bytes || (*now)["output_hash"] != string("output_hash"))
    return {};
  return Finished{*vertices, *triangles};
}

// Jobs wait here, after reading their maps, until the memory their build needs fits under the
// budget beside the builds already running; the first one always runs.
class MemoryGate {
 public:
  explicit MemoryGate(std::uint64_t budget) : budget_(budget) {}
  void acquire(std::uint64_t bytes) {
    std::unique_lock<std::mutex> lock(mutex_);
    fits_.wait(lock, [&] { return held_ == 0 || held_ + bytes <= budget_; });
    held_ += bytes;
  }
  void release(std::uint64_t bytes) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      held_ -= bytes;
    }
    fits_.notify_all();
  }

 private:
  std::mutex mutex_;
  std::condition_variable fits_;
  std::uint64_t budget_;
  std::uint64_t held_ = 0;
};

enum class JobStatus { ok, skipped, failed };

struct Outcome {
  JobStatus status = JobStatus::failed;
  int exit_code = 0;  // of a failed job: 1 invalid volume, 2 bad input
  std::string error;
  std::uint64_t vertices = 0, triangles = 0;
  double hash_seconds = 0;
  BuildJobResult build;  // its times
};

Outcome run_job(const Job& job, MemoryGate& gate) {
  Outcome out;
  if (!job.error.empty()) {
    out.exit_code = 2;
    out.error = job.error;
    return out;
  }
  const auto started = std::chrono::steady_clock::now();
  JobReads reads;
  const Result<std::string> hash = content_hash(job.options, &reads);
  out.hash_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  if (!hash) {
    out.exit_code = 2;
    out.error = hash.error().message;
    return out;
  }
  if (const std::optional<Finished> finished = finished_job(job.options, *hash)) {
    out.status = JobStatus::skipped;
    out.vertices = finished->vertices;
    out.triangles = finished->triangles;
    return out;
  }
  // What this job holds of the gate, released however the build ends (an exception too), or the
  // jobs after it could wait forever.
  struct Held {
    MemoryGate& gate;
    std::uint64_t bytes = 0;
    ~Held() { gate.release(bytes); }
  } held{gate};
  BuildJobHooks hooks;
  hooks.extra_report = {{"job_hash", *hash}};
  hooks.light_text = &reads.light;
  if (!job.options.medium_path.empty()) hooks.medium_text = &reads.medium;
  hooks.after_read = [&reads] { return images_unchanged(reads); };
  hooks.volume_written = output_keys;
  hooks.before_build = [&](const ShadowMaps& maps, BuildMemory mode) {
    const std::uint64_t bytes =
        build_memory_bytes(mode, maps.width(), maps.height(), maps.omni ? kOmniFaces : 1);
    gate.acquire(bytes);
    held.bytes = bytes;
  };
  Progress progress(true);
  out.build = run_build_job(job.options, progress, hooks);
  out.exit_code = out.build.exit_code;
  out.error = out.build.error;
  out.status = out.exit_code == 0 ? JobStatus::ok : JobStatus::failed;
  out.vertices = out.build.vertices;
  out.triangles = out.build.triangles;
  return out;
}

std::string result_line(const Job& job, const Outcome& o) {
  const BuildJobResult& b = o.build;
  const bool failed = o.status == JobStatus::failed;
  ordered_json line = {
      {"line", job.line},
      {"id", job.id},
      {"status", o.status == JobStatus::ok        ? "ok"
                 : o.status == JobStatus::skipped ? "skipped"
                                                  : "failed"},
      {"out", job.out},
      {"vertices", failed ? ordered_json(nullptr) : ordered_json(o.vertices)},
      {"triangles", failed ? ordered_json(nullptr) : ordered_json(o.triangles)},
      {"seconds",
       {{"hash", o.hash_seconds},
        {"read", b.read_seconds},
        {"wait", b.wait_seconds},
        {"build", b.build_seconds},
        {"check", b.check_seconds},
        {"write", b.write_seconds}}},
      {"error", o.error.empty() ? ordered_json(nullptr) : ordered_json(with_flags(o.error))}};
  return json_text(line);
}

// No output of the run may be one of its inputs (compared by core/path.h file_identity: the same
// inode, or the same new path): a job whose out or report is read by any job, or is the jobs file,
// fails; --results naming an input, the jobs file or a job's output stops the batch, returning its
// message ("" when nothing clashes). `written`: each job output's identity and its job's line.
std::string check_outputs(const BatchOptions& opts, std::vector<Job>& all,
                          const std::unordered_map<std::string, int>& written) {
  std::unordered_map<std::string, std::string> read;  // identity: what reads it
  read.emplace(file_identity(opts.jobs_path), "the jobs file");
  for (const Job& job : all)
    if (job.error.empty())
      for (const auto& [key, path] : input_files(job.options))
        read.emplace(file_identity(path), path + ", an input of line " + std::to_string(job.line) +
                                              " (key '" + key + "')");
  for (Job& job : all) {
    if (!job.error.empty()) continue;
    for (const std::string* out : {&job.options.out_path, &job.options.report_path})
      if (const auto input = read.find(file_identity(*out)); input != read.end()) {
        job.error = job_where(opts.jobs_path, job.line) + ": " + *out + ": is also " +
                    input->second + "; an output may not replace an input";
        break;
      }
  }
  if (opts.results_path.empty()) return {};
  const std::string results = file_identity(opts.results_path);
  if (const auto input = read.find(results); input != read.end())
    return "--results " + opts.results_path + ": is also " + input->second +
           "; an output may not replace an input";
  if (const auto output = written.find(results); output != written.end())
    return "--results " + opts.results_path + ": is also an output of line " +
           std::to_string(output->second) + "; give the results their own file";
  return {};
}

int run_batch(const BatchOptions& opts) {
  Result<Shard> shard = !opts.shard_given ? Result<Shard>(Shard{}) : parse_shard(opts.shard);
  if (!shard) return fail(shard.error().message);
  std::unordered_map<std::string, int> written;  // each output's identity, and its job's line
  Result<std::vector<Job>> jobs = read_jobs(opts.jobs_path, &written);
  if (!jobs) return fail(jobs.error().message);
  std::vector<Job>& all = *jobs;
  if (const std::string clash = check_outputs(opts, all, written); !clash.empty())
    return fail(clash);

  std::vector<const Job*> mine;  // this shard's: job i belongs to shard i mod N
  for (const Job& job : all)
    if (static_cast<long>(job.number % static_cast<std::size_t>(shard->count)) == shard->index)
      mine.push_back(&job);

  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const int workers = static_cast<int>(
      std::min<std::size_t>(std::min(opts.jobs > 0 ? opts.jobs : cores, kMaxParallelJobs),
                            std::max<std::size_t>(1, mine.size())));
  MemoryGate gate(memory_budget());
  const bool tty = ::isatty(STDERR_FILENO) != 0;
  const auto started = std::chrono::steady_clock::now();

  std::mutex mutex;  // guards what follows, and the output
  std::vector<std::optional<Outcome>> outcomes(mine.size());
  std::vector<std::string> lines;  // for --results
  std::size_t emitted = 0, done = 0, ok = 0, skipped = 0, failed = 0;
  int exit_code = 0;
  std::atomic<std::size_t> next{0};
  auto worker = [&] {
    for (std::size_t i; (i = next.fetch_add(1)) < mine.size();) {
      const Job& job = *mine[i];
      Outcome o;
      try {
        o = run_job(job, gate);
      } catch (const std::bad_alloc&) {
        o.exit_code = 2;
        o.error = "out of memory";
      } catch (const std::exception& e) {
        o.exit_code = 2;
        o.error = e.what();
      }
      // A build's errors name its files; the job's line goes first.
      if (o.status == JobStatus::failed && job.error.empty())
        o.error = job_where(opts.jobs_path, job.line) + ": " + o.error;
      std::lock_guard<std::mutex> lock(mutex);
      ++done;
      if (o.status == JobStatus::ok) ++ok;
      if (o.status == JobStatus::skipped) ++skipped;
      if (o.status == JobStatus::failed) {
        ++failed;
        exit_code = std::max(exit_code, o.exit_code);
        if (!opts.quiet)
          std::fprintf(stderr, "%slightvol: %s\n", tty ? "\r\033[K" : "",
                       printable(with_flags(o.error)).c_str());
      }
      if (!opts.quiet && tty)
        std::fprintf(stderr, "\r\033[Kbatch: %zu/%zu done, %zu failed", done, mine.size(), failed);
      outcomes[i] = std::move(o);
      // Result lines in job order, each as soon as it and every job before it are done.
      for (; emitted < mine.size() && outcomes[emitted]; ++emitted) {
        const std::string line = result_line(*mine[emitted], *outcomes[emitted]);
        if (opts.results_path.empty()) {
          std::printf("%s\n", line.c_str());
          std::fflush(stdout);
        } else {
          lines.push_back(line);
        }
        outcomes[emitted]->build = {};  // the report is no longer needed
      }
    }
  };
  std::vector<std::thread> threads;
  for (int t = 1; t < workers; ++t) threads.emplace_back(worker);
  worker();
  for (std::thread& t : threads) t.join();

  if (!opts.results_path.empty()) {
    std::string all_lines;
    for (const std::string& line : lines) all_lines += line + "\n";
    if (Status s = write_bytes_atomically(opts.results_path, all_lines); !s)
      return fail(s.error().message);
  }
  if (!opts.quiet) {
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    const std::string which = !opts.shard_given
                                  ? std::to_string(mine.size()) + " jobs"
                                  : "shard " + opts.shard + ": " + std::to_string(mine.size()) +
                                        " of " + std::to_string(all.size()) + " jobs";
    std::fprintf(stderr, "%sbatch: %s: %zu ok, %zu skipped, %zu failed, %.2f s\n",
                 tty ? "\r\033[K" : "", which.c_str(), ok, skipped, failed, seconds);
  }
  return exit_code;
}

}  // namespace

void add_batch_command(CLI::App& app, Runner* run) {
  auto o = std::make_shared<BatchOptions>();
  CLI::App* cmd = app.add_subcommand(
      "batch", "Run many builds from a JSON-lines file, in parallel, one result line per job.");
  cmd->footer(
      "Each line of JOBS.jsonl is one build: {\"id\": \"a\", \"inputs\": [\"a.exr\"], \"light\": "
      "\"l.json\",\n"
      "\"out\": \"a.ply\", \"args\": [\"--adaptive\", \"--max-error\", \"0.01\"]}; args are "
      "build's flags.\n"
      "Paths are relative to the jobs file's folder. Blank lines and lines starting with # are "
      "skipped.\n"
      "A job whose output and report (<out>.report.json) exist with the same content hash, and "
      "whose\noutput still has the size and hash its report recorded, is skipped.\n"
      "Results: one JSON line per job on stdout, in job order. Exit 0 when every job is ok or "
      "skipped,\n"
      "1 when a volume failed its checks, 2 when a job had bad input. See docs/batch.md.");
  cmd->add_option("jobfile", o->jobs_path, "The jobs (JOBS.jsonl): one JSON object per line")
      ->required();
  cmd->add_option("--jobs,-j", o->jobs, "Jobs run at once (default: one per core; at most 64)")
      ->check(decimal_integer())
      ->check(CLI::Range(1, kMaxParallelJobs));
  cmd->add_option("--shard", o->shard,
                  "Run the K-th of N slices, K/N (0 <= K < N): the jobs i with i mod N = K");
  cmd->add_option(
      "--results", o->results_path,
      "Write the result lines to this file (atomically, at the end) instead of stdout (- for "
      "stdout, at the end)");
  cmd->add_flag("--quiet,-q", o->quiet, "No progress, failures or summary on stderr");
  cmd->callback([o, run, cmd] {
    o->shard_given = cmd->count("--shard") > 0;
    *run = [o] { return run_batch(*o); };
  });
}

}  // namespace lightvol::cli
