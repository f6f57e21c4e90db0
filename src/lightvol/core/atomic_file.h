// Atomic output: a file appears whole under its name, or not at all.
#pragma once

#include <functional>
#include <string>
#include <string_view>

#include <lightvol/core/result.h>

namespace lightvol {

// Calls `write(temp_path)` to create a temporary file beside `path` (same directory, same
// extension, so format-by-extension writers still pick the right format), then renames it onto
// `path`. If `write` fails or throws, the temporary file is removed and `path` is left untouched.
Status write_file_atomically(const std::string& path,
                             const std::function<Status(const std::string& temp_path)>& write);

// Writes `bytes` to `path` atomically.
Status write_bytes_atomically(const std::string& path, std::string_view bytes);

}  // namespace lightvol
