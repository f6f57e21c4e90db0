// Small text files read whole, once: the JSON descriptions (light, medium, camera). A caller that
// needs the bytes themselves (batch hashes a light's bytes and parses those same bytes) reads
// them here, as load_light and load_medium do.
#pragma once

#include <cstddef>
#include <string>

#include <lightvol/core/result.h>

namespace lightvol {

// The most bytes read_text_file reads.
inline constexpr std::size_t kMaxTextFileBytes = std::size_t{64} << 20;

// The whole text of the file at `path`, read once; `what` names it in errors ("light
// description"). Pipes (a shell's <(...)) are read to their end; a directory is refused, and so
// is anything longer than 64 MiB (`/dev/zero` ends there instead of reading forever).
Result<std::string> read_text_file(const std::string& path, const char* what);

}  // namespace lightvol
