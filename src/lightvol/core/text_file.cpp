#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <lightvol/core/text_file.h>

namespace lightvol {

Result<std::string> read_text_file(const std::string& path, const char* what) {
  // Pipes (a shell's <(...)) are fine; directories are not, and devices that never end are cut
  // off: descriptions are small.
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    return Error{path + ": is a directory, not a " + std::string(what)};
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{path + ": cannot open " + what + ": " + std::strerror(errno)};
  std::string text;
  char buffer[1 << 16];
  while (in.read(buffer, sizeof buffer) || in.gcount() > 0) {
    text.append(buffer, static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxTextFileBytes)
      return Error{path + ": is larger than 64 MiB; a " + std::string(what) +
                   " is a small JSON file"};
  }
  if (in.bad()) return Error{path + ": cannot read " + what};
  return text;
}

}  // namespace lightvol
