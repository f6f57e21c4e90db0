#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <lightvol/core/atomic_file.h>

namespace lightvol {
namespace fs = std::filesystem;

namespace {
std::string temp_name_for(const fs::path& target) {
  static std::atomic<unsigned> counter{0};
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  const std::string name = "." + target.stem().string() + ".lightvol-tmp-" +
                           std::to_string(::getpid()) + "-" + std::to_string(counter++) +
                           target.extension().string();
  return (dir / name).string();
}
}  // namespace

Status write_file_atomically(const std::string& path,
                             const std::function<Status(const std::string& temp_path)>& write) {
  const fs::path target(path);
  std::error_code ec;
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  if (!fs::is_directory(dir, ec))
    return Error{path + ": directory " + dir.string() + " does not exist"};
  if (fs::is_directory(target, ec)) return Error{path + ": is a directory"};
  // The finished file is renamed over the target: that would replace a device or a pipe
  // (/dev/stdout) with a plain file.
  if (const fs::file_status st = fs::status(target, ec); fs::exists(st) && !fs::is_regular_file(st))
    return Error{path +
                 ": exists and is not a regular file (a device or a pipe); outputs are "
                 "written to files"};

  const std::string temp = temp_name_for(target);
  Status status;
  try {
    status = write(temp);
  } catch (const std::bad_alloc&) {
    status = Error{path + ": out of memory while writing"};
  } catch (const std::exception& e) {
    status = Error{path + ": " + e.what()};
  }
  if (status.ok() && !fs::is_regular_file(temp, ec))
    status = Error{path + ": the writer produced no file"};
  if (!status.ok()) {
    fs::remove(temp, ec);
    return status;
  }
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    fs::remove(temp, ec);
    return Error{path + ": cannot move the finished file into place: " + why};
  }
  return {};
}

Status write_bytes_atomically(const std::string& path, std::string_view bytes) {
  return write_file_atomically(path, [&](const std::string& temp) -> Status {
    std::FILE* f = std::fopen(temp.c_str(), "wb");
    if (!f) return Error{path + ": cannot create file: " + std::strerror(errno)};
    const bool ok = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
    const bool closed = std::fclose(f) == 0;
    if (!ok || !closed) return Error{path + ": write failed: " + std::strerror(errno)};
    return {};
  });
}

}  // namespace lightvol
