#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <climits>
#include <filesystem>

#include <lightvol/core/path.h>

namespace lightvol {
namespace fs = std::filesystem;

namespace {

constexpr int kMaxLinks = 40;  // as the kernel's path walk allows

// N of "<prefix>N" (N up to 9 digits), or -1.
int descriptor_after(const std::string& path, const std::string& prefix) {
  if (path.size() <= prefix.size() || path.size() > prefix.size() + 9 ||
      path.compare(0, prefix.size(), prefix) != 0)
    return -1;
  const std::string digits = path.substr(prefix.size());
  if (!std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
    return -1;
  return std::stoi(digits);
}

// The descriptor `path` itself spells (no links followed), or -1.
int spelled_descriptor(const std::string& path) {
  if (path == "-") return 1;
  const std::string p = fs::path(path).lexically_normal().string();
  if (p == "/dev/stdout") return 1;
  if (p == "/dev/stderr") return 2;
  for (const std::string& prefix :
       {std::string("/dev/fd/"), std::string("/proc/self/fd/"),
        std::string("/proc/thread-self/fd/"), "/proc/" + std::to_string(::getpid()) + "/fd/"})
    if (const int fd = descriptor_after(p, prefix); fd >= 0) return fd;
  return -1;
}

// The link `path` holds, resolved against its folder; "" when `path` is not a symlink.
std::string read_link(const std::string& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0 || !S_ISLNK(st.st_mode)) return {};
  char buffer[PATH_MAX];
  const ssize_t n = ::readlink(path.c_str(), buffer, sizeof buffer);
  if (n <= 0 || static_cast<std::size_t>(n) >= sizeof buffer) return {};
  const fs::path link(std::string(buffer, static_cast<std::size_t>(n)));
  if (link.is_absolute()) return link.string();
  const fs::path dir = fs::path(path).parent_path();
  return (dir.empty() ? link : dir / link).string();
}

}  // namespace

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

int named_descriptor(const std::string& path) {
  std::string p = path;
  for (int links = 0; links <= kMaxLinks; ++links) {
    if (const int fd = spelled_descriptor(p); fd >= 0) return fd;
    p = read_link(p);
    if (p.empty()) return -1;
  }
  return -1;
}

Result<std::string> follow_links(const std::string& path) {
  std::string p = path;
  for (int links = 0; links <= kMaxLinks; ++links) {
    std::string next = read_link(p);
    if (next.empty()) return p;
    p = std::move(next);
  }
  return Error{path + ": too many levels of symbolic links"};
}

std::string control_character_in(const std::string& path) {
  for (std::size_t i = 0; i < path.size(); ++i) {
    const auto byte = static_cast<unsigned char>(path[i]);
    if (byte >= 32 && byte != 127) continue;
    static constexpr char kHex[] = "0123456789abcdef";
    return std::string("control character \\x") + kHex[byte >> 4] + kHex[byte & 15] + " at byte " +
           std::to_string(i);
  }
  return {};
}

std::string file_identity(const std::string& path) {
  struct stat st {};
  bool found = false;
  if (const int fd = named_descriptor(path); fd >= 0)
    found = ::fstat(fd, &st) == 0;
  else
    found = ::stat(path.c_str(), &st) == 0;
  if (found) return "inode " + std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino);
  const Result<std::string> followed = follow_links(path);
  const fs::path target(followed ? *followed : path);
  std::error_code ec;
  const fs::path absolute = fs::absolute(target, ec);
  const fs::path canonical = fs::weakly_canonical(absolute, ec);
  return "path " + (ec ? absolute.lexically_normal().string() : canonical.string());
}

}  // namespace lightvol
