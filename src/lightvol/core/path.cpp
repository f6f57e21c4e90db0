#include <algorithm>
#include <cctype>
#include <filesystem>

#include <lightvol/core/path.h>

namespace lightvol {

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

}  // namespace lightvol
