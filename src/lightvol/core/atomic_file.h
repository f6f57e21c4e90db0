// Atomic output: a file appears whole under its name, or not at all; the outputs of one run appear
// together, or none does.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <string_view>

#include <lightvol/core/result.h>

namespace lightvol {

// Calls `write(temp_path)` to fill a temporary file beside `path`, then renames it onto `path`.
// The temporary file is created exclusively (O_EXCL | O_NOFOLLOW) under an unguessable name in
// the same directory, short enough to fit wherever `path`'s name fits, with `path`'s extension (so
// format-by-extension writers still pick the right format); `write` opens it by name and
// overwrites it (without creating it: it exists, empty; a signal's cleanup may unlink it while
// another thread is about to open it, and an open that creates would leave it behind). If `path`
// exists, the result keeps its permission bits. If `write` fails or throws, the temporary file is
// removed and `path` is left untouched. SIGINT, SIGTERM and SIGHUP while the temporary file exists
// remove it before the process dies (unless the program handles or ignores those signals itself).
//
// Where the output lands (core/path.h): a symlink is followed to the file it leads to; the
// temporary is made beside that file and renamed onto it, and the symlink stays a symlink. A path
// naming a descriptor ("-" for standard output, /dev/stdout, /dev/fd/N, /proc/self/fd/N), a
// character device (a terminal, /dev/null) or a pipe is written through, never replaced: `write`
// fills a temporary in the system's temporary folder (TMPDIR), whose bytes are then copied to it
// (removed as the copy starts); write_bytes_atomically writes its bytes straight through. A block
// device or a socket is refused.
//
// Temporaries a killed process left (SIGKILL cannot be caught) are removed later: the first write
// of a process into a folder (or, for a stream, into the temporary folder) first removes the
// files there named as this library names its temporaries (".lv-", 16 of [a-z0-9], then the
// extension) that are regular files with one link, unchanged for an hour: older than any live
// writer leaves one between writes (docs/robustness.md).
//
// While an OutputTransaction is open on this thread, the finished file is not renamed yet: it is
// staged in the transaction, and appears under `path` when the transaction commits.
Status write_file_atomically(const std::string& path,
                             const std::function<Status(const std::string& temp_path)>& write);

// Writes `bytes` to `path` atomically (see write_file_atomically).
Status write_bytes_atomically(const std::string& path, std::string_view bytes);

// All outputs of a run, committed together. Open one before writing the outputs; every
// write_file_atomically on this thread until it is destroyed stages its file here. commit() renames
// them all into place, or (if one rename fails) puts back what the others replaced and leaves every
// target as it was; then writes the streams (standard output, pipes) through, which cannot be
// taken back. A transaction destroyed without commit() removes what it staged. Two outputs naming
// the same file (core/path.h file_identity: the same inode, or the same new path) are an error at
// the second write.
class OutputTransaction {
 public:
  OutputTransaction();
  ~OutputTransaction();
  OutputTransaction(const OutputTransaction&) = delete;
  OutputTransaction& operator=(const OutputTransaction&) = delete;

  Status commit();

  // The temporary that holds the finished file staged for `path` (its bytes as they will appear
  // under `path` at commit), or "" when this transaction stages no file for `path` (nothing, or a
  // stream). For a caller that records what it wrote (batch: the volume's size and hash).
  std::string staged_file(const std::string& path) const;

  struct Impl;

  // Stages another thread's outputs in this transaction: while a Writer made from it lives on a
  // thread, write_file_atomically on that thread stages its files here, as it would on the
  // transaction's own thread. One writer thread at a time, while the transaction's own thread
  // writes nothing and neither commits nor destroys it; join the writer thread first (a build
  // writes its volume this way while its check runs, pipeline/build_file.cpp).
  class Writer {
   public:
    explicit Writer(OutputTransaction& transaction);
    ~Writer();
    Writer(const Writer&) = delete;
    Writer& operator=(const Writer&) = delete;

   private:
    Impl* previous_;
  };

 private:
  Status commit_files();  // renames the staged files into place, all or nothing
  std::unique_ptr<Impl> impl_;
  Impl* previous_ = nullptr;  // the transaction this one is nested in
};

}  // namespace lightvol
