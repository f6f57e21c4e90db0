// Small helpers on file paths.
#pragma once

#include <string>

namespace lightvol {

// The extension of `path`'s file name with its dot, lower-cased ("scene.EXR" → ".exr"; "" when
// there is none), as std::filesystem::path::extension finds it.
std::string lower_extension(const std::string& path);

}  // namespace lightvol
