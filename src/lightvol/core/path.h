// Small helpers on file paths.
#pragma once

#include <string>

#include <lightvol/core/result.h>

namespace lightvol {

// The extension of `path`'s file name with its dot, lower-cased ("scene.EXR" → ".exr"; "" when
// there is none), as std::filesystem::path::extension finds it.
std::string lower_extension(const std::string& path);

// The open file descriptor an output path names, rather than a file: "-" is standard output (1);
// /dev/stdout, /dev/stderr, /dev/fd/N, /proc/self/fd/N, /proc/thread-self/fd/N and
// /proc/<this process>/fd/N, or a symlink (or chain of them) leading to one, are 1, 2 or N.
// -1 when `path` names no descriptor. Whether N is open is not checked.
int named_descriptor(const std::string& path);

// `path` with its symlinks followed one by one (each link read and resolved against its own
// folder, up to 40 of them), as far as they lead: the path a write to `path` reaches, which may
// not exist yet (a link to a missing file leads to that file). An error for a loop.
Result<std::string> follow_links(const std::string& path);

// A text equal for two paths exactly when they name the same file: "inode D:I" (st_dev, st_ino)
// of an existing file (symlinks followed) or of the descriptor the path names (/dev/stdout);
// otherwise "path P", P the normalized absolute path of the file a write would create there.
std::string file_identity(const std::string& path);

// Where `path` holds a control character (a byte below 32, or 127: NUL, a line break, an escape),
// which no path lightvol reads or writes may hold, as "control character \xNN at byte K" (K from
// 0); "" when it holds none.
std::string control_character_in(const std::string& path);

}  // namespace lightvol
