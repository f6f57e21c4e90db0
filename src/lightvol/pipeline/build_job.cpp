#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <memory>
#include <new>
#include <optional>
#include <thread>

#include <nlohmann/json.hpp>

#include <lightvol/core/limits.h>
#include <lightvol/core/text_file.h>
#include <lightvol/depth/cube_faces.h>
#include <lightvol/pipeline/build_job.h>
#include <lightvol/pipeline/detail/build_hooks.h>

#ifndef LIGHTVOL_VERSION
#error "LIGHTVOL_VERSION: the project's version, set by src/CMakeLists.txt"
#endif

namespace lightvol {
namespace {
namespace fs = std::filesystem;

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

// Feeds the regular file at `path` to `add` a chunk at a time, refusing what a build refuses
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
Result<std::string> content_hash(const BuildJob& job, JobReads* reads) {
  Hasher all;
  auto add = [&](const std::string& bytes) {
    const std::uint64_t size = bytes.size();
    all.add(&size, sizeof size);
    all.add(bytes.data(), bytes.size());
  };
  add(std::string("lightvol ") + LIGHTVOL_VERSION);
  add(job.options_key);
  for (const auto& [key, path] : build_input_files(job.options)) {
    std::uint64_t size = 0;
    const std::uint64_t marker = ~std::uint64_t{0};  // a file, then its length after its bytes
    all.add(&marker, sizeof marker);
    if (key == "inputs") {
      Hasher file;
      HashedFile hashed{key, path};
      const Status read = hash_image_file(
          key, path,
          [&](const char* bytes, std::size_t n) {
            all.add(bytes, n);
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
      all.add(text->data(), text->size());
      size = text->size();
      (light ? reads->light : reads->medium) = std::move(*text);
    }
    all.add(&size, sizeof size);
  }
  return hex_digest(all.digest());
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

// What a skipped job's result says: the counts its report recorded.
struct Finished {
  std::uint64_t vertices = 0, triangles = 0;
};

// The counts of an earlier run, when its report vouches for this job as the files are now: the
// output and its report are regular files; the report is a JSON object whose job_hash is `hash`,
// whose vertices and triangles are counts (integers >= 0), and whose output_bytes and output_hash
// are the output's size and hash now. Anything else (a missing, truncated or replaced output, a
// report hand-edited or cut) is no vouching: the job runs again and writes both anew.
std::optional<Finished> finished_job(const BuildFileOptions& o, const std::string& hash) {
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

BuildJobResult run_job(const BuildJob& job, MemoryGate& gate) {
  BuildJobResult out;
  const auto started = std::chrono::steady_clock::now();
  JobReads reads;
  const Result<std::string> hash = content_hash(job, &reads);
  out.hash_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  if (!hash) {
    out.error = hash.error();
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
  BuildFileOptions options = job.options;
  options.light_text = &reads.light;
  if (!options.medium_path.empty()) options.medium_text = &reads.medium;
  detail::BuildFileHooks hooks;
  hooks.extra_report = {{"job_hash", *hash}};
  hooks.after_read = [&reads] { return images_unchanged(reads); };
  hooks.volume_written = output_keys;
  hooks.before_build = [&](const ShadowMaps& maps, BuildMemory mode) {
    const std::uint64_t bytes =
        build_memory_bytes(mode, maps.width(), maps.height(), maps.omni ? kOmniFaces : 1);
    gate.acquire(bytes);
    held.bytes = bytes;
  };
  StageLog log;
  BuildFileResult built = detail::build_volume_file(options, log, hooks);
  out.seconds = built.seconds;
  if (!built.status) {
    out.error = built.status.error();
    return out;
  }
  out.status = JobStatus::ok;
  out.vertices = built.vertices;
  out.triangles = built.triangles;
  return out;
}

}  // namespace

std::vector<std::pair<std::string, std::string>> build_input_files(const BuildFileOptions& o) {
  std::vector<std::pair<std::string, std::string>> files;
  for (const std::string& path : depth_input_files(o.depth_paths))
    files.emplace_back("inputs", path);
  files.emplace_back("light", o.light_path);
  if (!o.medium_path.empty()) files.emplace_back("args: --medium", o.medium_path);
  return files;
}

void MemoryGate::acquire(std::uint64_t bytes) {
  std::unique_lock<std::mutex> lock(mutex_);
  fits_.wait(lock, [&] { return held_ == 0 || held_ + bytes <= budget_; });
  held_ += bytes;
}

void MemoryGate::release(std::uint64_t bytes) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    held_ -= bytes;
  }
  fits_.notify_all();
}

BuildJobResult run_build_job(const BuildJob& job, MemoryGate& gate) {
  BuildJobResult result;
  if (!job.refused.empty()) {
    result.error = Error{job.refused};
    return result;
  }
  try {
    result = run_job(job, gate);
  } catch (const std::bad_alloc&) {
    result = {};
    result.error = Error{"out of memory"};
  } catch (const std::exception& e) {
    result = {};
    result.error = Error{e.what()};
  }
  // A build's errors name its files; the job's line goes first.
  if (result.status == JobStatus::failed)
    result.error.message = job.where + ": " + result.error.message;
  return result;
}

void run_build_jobs(const std::vector<const BuildJob*>& jobs, int workers,
                    const std::function<void(std::size_t, const BuildJobResult&)>& finished,
                    const std::function<void(std::size_t, const BuildJobResult&)>& in_order) {
  MemoryGate gate(memory_budget());
  std::mutex mutex;  // guards what follows, and the callbacks
  std::vector<std::optional<BuildJobResult>> results(jobs.size());
  std::size_t emitted = 0;
  std::atomic<std::size_t> next{0};
  auto worker = [&] {
    for (std::size_t i; (i = next.fetch_add(1)) < jobs.size();) {
      BuildJobResult result = run_build_job(*jobs[i], gate);
      std::lock_guard<std::mutex> lock(mutex);
      finished(i, result);
      results[i] = std::move(result);
      for (; emitted < jobs.size() && results[emitted]; ++emitted)
        in_order(emitted, *results[emitted]);
    }
  };
  std::vector<std::thread> threads;
  for (int t = 1; t < workers; ++t) threads.emplace_back(worker);
  worker();
  for (std::thread& t : threads) t.join();
}

}  // namespace lightvol
