#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <mutex>

#include <lightvol/core/buffer.h>
#include <lightvol/core/detail/image_helper.h>

#ifndef LIGHTVOL_IMAGE_HELPER_INSTALLED
#define LIGHTVOL_IMAGE_HELPER_INSTALLED ""
#endif
#ifndef LIGHTVOL_IMAGE_HELPER_BUILT
#define LIGHTVOL_IMAGE_HELPER_BUILT ""
#endif
#ifndef LIGHTVOL_EXR_HELPER_INSTALLED
#define LIGHTVOL_EXR_HELPER_INSTALLED ""
#endif
#ifndef LIGHTVOL_EXR_HELPER_BUILT
#define LIGHTVOL_EXR_HELPER_BUILT ""
#endif

namespace lightvol::detail {
namespace {

std::atomic<ImageServer> in_process_server{nullptr};
std::atomic<ImageServer> in_process_exr_server{nullptr};

// How long lightvol-image may take to load (about 0.2 s on a quiet machine; its 260 libraries on a
// loaded one take longer): a backstop, apart from the limits of each request.
constexpr double kStartSeconds = 60;

// Idle lightvol-image servers. A request takes one (or starts one when none is idle: concurrent
// readers each get their own) and puts it back when it answered whole; a server that failed has
// ended. At most kIdle are kept, as many as `lightvol batch` runs jobs at once (64), so that its
// jobs reuse their servers instead of starting and closing one per image; there are never more
// servers than callers that were reading at the same time. The rest are closed. At exit the idle
// ones are closed and reaped (so that a process's resource usage includes theirs, and none outlives
// it).
class ServerPool {
 public:
  static constexpr std::size_t kIdle = 64;
  std::unique_ptr<IsolatedServer> take() {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (idle_.empty()) return nullptr;
    std::unique_ptr<IsolatedServer> server = std::move(idle_.back());
    idle_.pop_back();
    return server;
  }
  void give_back(std::unique_ptr<IsolatedServer> server) {
    if (!server->alive()) return;
    const std::lock_guard<std::mutex> lock(mutex_);
    if (idle_.size() < kIdle) idle_.push_back(std::move(server));
  }
  void clear() {
    std::vector<std::unique_ptr<IsolatedServer>> idle;
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      idle.swap(idle_);
    }
  }

 private:
  std::mutex mutex_;
  std::vector<std::unique_ptr<IsolatedServer>> idle_;
};

// One pool for each program (ImageProgram).
ServerPool& server_pool(ImageProgram program = ImageProgram::image) {
  static ServerPool* const pools = [] {
    auto* created = new ServerPool[2];
    std::atexit([] {
      server_pool(ImageProgram::image).clear();
      server_pool(ImageProgram::exr).clear();
    });
    return created;
  }();
  return pools[program == ImageProgram::exr ? 1 : 0];
}

bool executable(const std::string& path) {
  std::error_code ec;
  return !path.empty() && std::filesystem::is_regular_file(path, ec) &&
         ::access(path.c_str(), X_OK) == 0;
}

// Where a reader program `name` may be, in order: beside the running program, in the libexec
// folder of its install prefix, where it was installed, where it was built.
std::vector<std::string> program_candidates(const char* name, const char* installed,
                                            const char* built) {
  std::vector<std::string> tried;
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    tried.push_back((self.parent_path() / name).string());
    tried.push_back((self.parent_path() / ".." / "libexec" / "lightvol" / name).lexically_normal());
  }
  tried.emplace_back(installed);
  tried.emplace_back(built);
  return tried;
}

}  // namespace

Result<std::string> image_helper_path() {
  if (const char* env = std::getenv("LIGHTVOL_IMAGE_HELPER"); env && *env) {
    if (executable(env)) return std::string(env);
    return Error{std::string("LIGHTVOL_IMAGE_HELPER names ") + env +
                 ", which is not an executable file"};
  }
  std::string where;
  for (const std::string& path : program_candidates(
           "lightvol-image", LIGHTVOL_IMAGE_HELPER_INSTALLED, LIGHTVOL_IMAGE_HELPER_BUILT)) {
    if (executable(path)) return path;
    if (!path.empty()) where += (where.empty() ? "" : ", ") + path;
  }
  return Error{"cannot find lightvol-image, the program that reads and writes images (looked at " +
               where + "); set LIGHTVOL_IMAGE_HELPER to its path"};
}

std::optional<std::string> exr_helper_path() {
  if (const char* env = std::getenv("LIGHTVOL_EXR_HELPER"); env && *env) {
    if (executable(env)) return std::string(env);
    return {};
  }
  if (const char* env = std::getenv("LIGHTVOL_IMAGE_HELPER"); env && *env) return {};
  for (const std::string& path :
       program_candidates("lightvol-exr", LIGHTVOL_EXR_HELPER_INSTALLED, LIGHTVOL_EXR_HELPER_BUILT))
    if (executable(path)) return path;
  return {};
}

bool exr_helper_available() {
  if (in_process_exr_server.load() != nullptr) return true;
  if (in_process_server.load() != nullptr) return false;
  return exr_helper_path().has_value();
}

void set_in_process_image_server(ImageServer server) { in_process_server.store(server); }

void set_in_process_exr_server(ImageServer server) { in_process_exr_server.store(server); }

void close_idle_image_servers() {
  server_pool(ImageProgram::image).clear();
  server_pool(ImageProgram::exr).clear();
}

Status run_image_helper(const std::string& what, const IsolationLimits& limits,
                        const std::function<Status(ChildInput&)>& parent, ImageProgram program) {
  const bool exr = program == ImageProgram::exr;
  if (const ImageServer server = (exr ? in_process_exr_server : in_process_server).load())
    return run_isolated(
        what, limits, [&](ChildOutput& channel) { server(channel, 1); }, parent);
  std::unique_ptr<IsolatedServer> server = server_pool(program).take();
  if (!server) {
    Result<std::string> path = Error{""};
    if (exr) {
      const std::optional<std::string> found = exr_helper_path();
      if (!found) return Error{what + ": cannot find lightvol-exr"};
      path = *found;
    } else {
      path = image_helper_path();
    }
    if (!path) return Error{what + ": " + path.error().message};
    Result<std::unique_ptr<IsolatedServer>> started =
        IsolatedServer::start(exr ? "lightvol-exr" : "lightvol-image", {*path}, kStartSeconds);
    if (!started) return Error{what + ": " + started.error().message};
    server = std::move(*started);
  }
  Status answer = server->request(what, limits, parent);
  server_pool(program).give_back(std::move(server));
  return answer;
}

ImageWriteResult write_image_file(const std::string& create_name, const std::string& temp,
                                  const ImageWrite& image) {
  ImageWriteResult result;
  const std::size_t values = static_cast<std::size_t>(image.width) *
                             static_cast<std::size_t>(image.height) *
                             static_cast<std::size_t>(image.channels);
  const auto parent = [&](ChildInput& in) -> Status {
    const bool floats = image.floats != nullptr;
    bool sent = in.write_value(ImageRequest::write) && in.write_string(create_name) &&
                in.write_string(temp) && in.write_value(std::int32_t{image.width}) &&
                in.write_value(std::int32_t{image.height}) &&
                in.write_value(std::int32_t{image.channels}) && in.write_value(image.stored) &&
                in.write_value(std::uint8_t{floats ? std::uint8_t{0} : std::uint8_t{1}}) &&
                in.write_value(static_cast<std::uint32_t>(image.names.size()));
    for (const std::string& name : image.names) sent = sent && in.write_string(name);
    sent = sent && (floats ? in.write(image.floats, values * sizeof(float))
                           : in.write(image.bytes, values));
    std::uint8_t outcome = 0;
    if (!sent || !in.read_value(&outcome) || outcome > 2 || !in.read_string(&result.message))
      return Error{"lightvol-image broke off its answer"};
    result.outcome = static_cast<ImageWriteResult::Outcome>(outcome);
    return {};
  };
  IsolationLimits limits;
  limits.cpu_seconds = 30 + 100e-9 * static_cast<double>(values);
  limits.wall_seconds = 60 + 4 * limits.cpu_seconds;
  limits.memory = (std::uint64_t{256} << 20) + 4 * values * sizeof(float);
  if (Status run = run_image_helper(temp + ": OpenImageIO's writer", limits, parent); !run)
    return {ImageWriteResult::Outcome::failed, run.error().message};
  return result;
}

DecodedFloats::DecodedFloats(int shared_fd, std::size_t texels) : bytes_(texels * sizeof(float)) {
  if (shared_fd >= 0) {
    struct stat status {};
    if (::fstat(shared_fd, &status) == 0 && static_cast<std::uintmax_t>(status.st_size) == bytes_) {
      void* mapped = ::mmap(nullptr, bytes_, PROT_READ | PROT_WRITE, MAP_SHARED, shared_fd, 0);
      if (mapped != MAP_FAILED) values_ = static_cast<float*>(mapped), shared_ = true;
    }
    ::close(shared_fd);
  }
  if (!shared_) {
    own_ = std::make_unique_for_overwrite<float[]>(texels);
    values_ = own_.get();
  }
}

void DecodedFloats::unmap() {
  if (shared_ && values_ != nullptr) ::munmap(values_, bytes_);
  if (shared_) values_ = nullptr;
}

void DecodedFloats::send(ChildOutput& channel) const {
  channel.write_value(std::uint8_t{shared_});  // 1: in the shared memory; 0: follows
  if (!shared_) channel.write(values_, bytes_);
}

}  // namespace lightvol::detail
