// Shared by the fuzz targets: the input written to a temporary file with a chosen extension (the
// readers under test take paths, as the CLI does).
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace lightvol::fuzz {

// A file in the temporary directory holding `size` bytes, removed when this goes out of scope.
class TempInput {
 public:
  TempInput(const std::uint8_t* data, std::size_t size, const std::string& extension) {
    path_ = (std::filesystem::temp_directory_path() /
             ("lightvol_fuzz_" + std::to_string(::getpid()) + extension))
                .string();
    std::ofstream out(path_, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  ~TempInput() {
    std::error_code ec;
    std::filesystem::remove(path_, ec);
  }
  TempInput(const TempInput&) = delete;
  TempInput& operator=(const TempInput&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

}  // namespace lightvol::fuzz
