#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/core/atomic_file.h>
#include <lightvol/core/path.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

using test::slurp;

TEST(AtomicFile, WritesBytes) {
  test::TempDir dir;
  ASSERT_TRUE(write_bytes_atomically(dir.file("a.txt"), "hello").ok());
  EXPECT_EQ(slurp(dir.file("a.txt")), "hello");
  EXPECT_EQ(dir.entries(), 1);
}

TEST(AtomicFile, FailedWriteLeavesExistingFileAndNoTemporary) {
  test::TempDir dir;
  const std::string path = dir.write("keep.ply", "good");
  const Status s = write_file_atomically(path, [](const std::string& temp) -> Status {
    std::ofstream(temp) << "partial";
    return Error{"simulated failure"};
  });
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().message, "simulated failure");
  EXPECT_EQ(slurp(path), "good");
  EXPECT_EQ(dir.entries(), 1);
}

TEST(AtomicFile, ThrowingWriterIsAnErrorAndLeavesNothing) {
  test::TempDir dir;
  const Status s = write_file_atomically(dir.file("x.obj"), [](const std::string& temp) -> Status {
    std::ofstream(temp) << "partial";
    throw std::runtime_error("boom");
  });
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("boom"), std::string::npos);
  EXPECT_EQ(dir.entries(), 0);
}

TEST(AtomicFile, TemporaryKeepsTheExtension) {
  test::TempDir dir;
  std::string seen;
  ASSERT_TRUE(write_file_atomically(dir.file("mesh.stl"), [&](const std::string& temp) -> Status {
                seen = temp;
                std::ofstream(temp) << "x";
                return {};
              }).ok());
  EXPECT_EQ(seen.substr(seen.size() - 4), ".stl");
}

TEST(AtomicFile, MissingDirectoryIsNamed) {
  test::TempDir dir;
  const Status s = write_bytes_atomically(dir.file("nope/out.ply"), "x");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("does not exist"), std::string::npos) << s.error().message;
}

// Before: a FIFO was refused ("is not a regular file"). A pipe is written through, never
// replaced by a plain file.
TEST(AtomicFile, PipeIsWrittenThroughAndStaysAPipe) {
  test::TempDir dir;
  const std::string fifo = dir.file("pipe.ply");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const int reader = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
  ASSERT_GE(reader, 0);
  ASSERT_TRUE(write_bytes_atomically(fifo, "bytes ").ok());
  // A writer that opens its file by name: it fills a temporary elsewhere, copied to the pipe.
  ASSERT_TRUE(write_file_atomically(fifo, [](const std::string& temp) -> Status {
                std::ofstream(temp) << "and a file";
                return {};
              }).ok());
  char buffer[64] = {};
  const ssize_t n = ::read(reader, buffer, sizeof buffer);
  ::close(reader);
  EXPECT_EQ(std::string(buffer, n > 0 ? static_cast<std::size_t>(n) : 0), "bytes and a file");
  EXPECT_TRUE(std::filesystem::is_fifo(fifo));
  EXPECT_EQ(dir.entries(), 1);
}

// Before: the symlink was replaced by a plain file holding the output (as /dev/stdout was, for the
// whole machine), and the file it led to kept its old content.
TEST(AtomicFile, SymlinkToAFileElsewhereIsWrittenThroughAndStaysALink) {
  test::TempDir links, files;
  const std::string real = files.write("real.json", "old");
  const std::string link = links.file("report.json");
  ASSERT_EQ(::symlink(real.c_str(), link.c_str()), 0);
  ASSERT_TRUE(write_bytes_atomically(link, "new").ok());
  EXPECT_EQ(slurp(real), "new");
  EXPECT_TRUE(std::filesystem::is_symlink(link));
  EXPECT_EQ(links.entries(), 1);  // no temporary beside the link
  EXPECT_EQ(files.entries(), 1);

  // The same inside a transaction (build's volume and report), with a writer that opens by name.
  {
    OutputTransaction outputs;
    ASSERT_TRUE(write_file_atomically(link, [](const std::string& temp) -> Status {
                  std::ofstream(temp) << "newer";
                  return {};
                }).ok());
    ASSERT_TRUE(outputs.commit().ok());
  }
  EXPECT_EQ(slurp(real), "newer");
  EXPECT_TRUE(std::filesystem::is_symlink(link));
  EXPECT_EQ(links.entries(), 1);
  EXPECT_EQ(files.entries(), 1);
}

TEST(AtomicFile, SymlinkToAMissingFileCreatesItThere) {
  test::TempDir links, files;
  const std::string link = links.file("out.txt");
  ASSERT_EQ(::symlink(files.file("new.txt").c_str(), link.c_str()), 0);
  ASSERT_TRUE(write_bytes_atomically(link, "made").ok());
  EXPECT_EQ(slurp(files.file("new.txt")), "made");
  EXPECT_TRUE(std::filesystem::is_symlink(link));
  EXPECT_EQ(links.entries(), 1);
}

// What `--report /dev/stdout` with standard output redirected to a file meets, without touching
// the real /dev: a symlink to /proc/self/fd/N, N a file in another folder with bytes already
// written. Before: the temporary was made beside the link and renamed over it; the file got
// nothing.
TEST(AtomicFile, DescriptorPathsAreWrittenThroughAtTheirOffset) {
  test::TempDir links, files;
  const std::string real = files.file("stdout.txt");
  const int fd = ::open(real.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::write(fd, "before\n", 7), 7);
  const std::string link = links.file("stdout");
  ASSERT_EQ(::symlink(("/proc/self/fd/" + std::to_string(fd)).c_str(), link.c_str()), 0);
  ASSERT_TRUE(write_bytes_atomically(link, "report\n").ok());
  ASSERT_TRUE(write_file_atomically("/dev/fd/" + std::to_string(fd), [](const std::string& temp) {
                std::ofstream(temp) << "volume\n";
                return Status{};
              }).ok());
  ASSERT_EQ(::write(fd, "after\n", 6), 6);
  ::close(fd);
  EXPECT_EQ(slurp(real), "before\nreport\nvolume\nafter\n");
  EXPECT_TRUE(std::filesystem::is_symlink(link));
  EXPECT_EQ(links.entries(), 1);
  EXPECT_EQ(files.entries(), 1);
}

TEST(AtomicFile, ClosedOrReadOnlyDescriptorsAreRefused) {
  test::TempDir dir;
  const Status closed = write_bytes_atomically("/dev/fd/987", "x");
  ASSERT_FALSE(closed.ok());
  EXPECT_EQ(closed.error().message, "/dev/fd/987: descriptor 987 is not open");
  const std::string file = dir.write("in.txt", "keep");
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  ASSERT_GE(fd, 0);
  const std::string path = "/proc/self/fd/" + std::to_string(fd);
  const Status read_only = write_bytes_atomically(path, "x");
  ::close(fd);
  ASSERT_FALSE(read_only.ok());
  EXPECT_EQ(read_only.error().message,
            path + ": descriptor " + std::to_string(fd) + " is not open for writing");
  EXPECT_EQ(slurp(file), "keep");
}

TEST(AtomicFile, NamedDescriptors) {
  EXPECT_EQ(named_descriptor("-"), 1);
  EXPECT_EQ(named_descriptor("/dev/stdout"), 1);
  EXPECT_EQ(named_descriptor("/dev/stderr"), 2);
  EXPECT_EQ(named_descriptor("/dev/fd/7"), 7);
  EXPECT_EQ(named_descriptor("/proc/self/fd/12"), 12);
  EXPECT_EQ(named_descriptor("/proc/" + std::to_string(::getpid()) + "/fd/3"), 3);
  EXPECT_EQ(named_descriptor("./-"), -1);
  EXPECT_EQ(named_descriptor("/dev/fd/x"), -1);
  EXPECT_EQ(named_descriptor("/dev/null"), -1);
  test::TempDir dir;
  const std::string link = dir.file("out");
  ASSERT_EQ(::symlink("/dev/stderr", link.c_str()), 0);
  EXPECT_EQ(named_descriptor(link), 2);
}

// Before: the temporary was ".NAME.lightvol-tmp-PID-N.ext", opened without O_EXCL: a symlink
// planted there made the write go through it (overwriting the victim), and a directory planted
// there made the run fail.
TEST(AtomicFile, PlantedSymlinksAndDirectoriesAtPredictableNamesAreNotFollowed) {
  test::TempDir dir;
  const std::string victim = dir.write("victim.txt", "precious");
  for (int n = 0; n < 8; ++n) {
    const std::string old_name = "." + std::string("out") + ".lightvol-tmp-" +
                                 std::to_string(::getpid()) + "-" + std::to_string(n) + ".ply";
    ASSERT_EQ(::symlink(victim.c_str(), dir.file(old_name).c_str()), 0);
    const std::string old_dir =
        ".out.lightvol-tmp-" + std::to_string(::getpid()) + "-" + std::to_string(n + 8) + ".ply";
    ASSERT_EQ(::mkdir(dir.file(old_dir).c_str(), 0700), 0);
  }
  const int before = dir.entries();
  ASSERT_TRUE(write_bytes_atomically(dir.file("out.ply"), "new volume").ok());
  EXPECT_EQ(slurp(victim), "precious");
  EXPECT_EQ(slurp(dir.file("out.ply")), "new volume");
  struct stat st {};
  ASSERT_EQ(::lstat(dir.file("out.ply").c_str(), &st), 0);
  EXPECT_TRUE(S_ISREG(st.st_mode));
  EXPECT_EQ(dir.entries(), before + 1);
}

TEST(AtomicFile, TemporaryIsAFreshUnguessableFileOfItsOwn) {
  test::TempDir dir;
  std::vector<std::string> names;
  for (int i = 0; i < 2; ++i)
    ASSERT_TRUE(write_file_atomically(dir.file("m.ply"), [&](const std::string& temp) -> Status {
                  struct stat st {};
                  EXPECT_EQ(::lstat(temp.c_str(), &st), 0);
                  EXPECT_TRUE(S_ISREG(st.st_mode));  // created exclusively, not a planted link
                  EXPECT_EQ(st.st_size, 0);
                  EXPECT_EQ(st.st_nlink, 1u);
                  names.push_back(temp);
                  std::ofstream(temp) << "x";
                  return {};
                }).ok());
  EXPECT_NE(names[0], names[1]);
  EXPECT_EQ(names[0].find(std::to_string(::getpid())), std::string::npos) << names[0];
}

TEST(AtomicFile, ReplacedTemporaryIsAnError) {
  test::TempDir dir;
  const std::string victim = dir.write("victim.txt", "precious");
  const Status s = write_file_atomically(dir.file("o.ply"), [&](const std::string& temp) -> Status {
    ::unlink(temp.c_str());
    EXPECT_EQ(::symlink(victim.c_str(), temp.c_str()), 0);
    return {};
  });
  ASSERT_FALSE(s.ok());
  EXPECT_FALSE(std::filesystem::exists(dir.file("o.ply")));
  EXPECT_EQ(slurp(victim), "precious");
}

// Before: a 444 file replaced by a run became 644.
TEST(AtomicFile, ReplacingAFileKeepsItsMode) {
  test::TempDir dir;
  const std::string path = dir.write("ro.ply", "old");
  ASSERT_EQ(::chmod(path.c_str(), 0444), 0);
  ASSERT_TRUE(write_bytes_atomically(path, "new").ok());
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0444u);
  EXPECT_EQ(slurp(path), "new");
  const std::string exec = dir.write("x.ply", "old");
  ASSERT_EQ(::chmod(exec.c_str(), 0751), 0);
  ASSERT_TRUE(write_bytes_atomically(exec, "new").ok());
  ASSERT_EQ(::stat(exec.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0751u);
}

// Before: names of 234-255 bytes failed with "File name too long" (the temporary name was longer).
TEST(AtomicFile, LongestNamesWork) {
  test::TempDir dir;
  for (std::size_t length : {234u, 250u, 255u}) {
    const std::string name = std::string(length - 4, 'n') + ".ply";
    ASSERT_TRUE(write_bytes_atomically(dir.file(name), "v").ok()) << length;
    EXPECT_EQ(slurp(dir.file(name)), "v");
  }
  EXPECT_EQ(dir.entries(), 3);
}

TEST(AtomicFile, TransactionCommitsAllOrNothing) {
  test::TempDir dir;
  const std::string a = dir.write("a.ply", "old a");
  {
    OutputTransaction tx;
    ASSERT_TRUE(write_bytes_atomically(a, "new a").ok());
    EXPECT_EQ(slurp(a), "old a");  // staged, not yet in place
    ASSERT_FALSE(write_bytes_atomically(dir.file("missing/r.json"), "{}").ok());
    // no commit: the run failed
  }
  EXPECT_EQ(slurp(a), "old a");
  EXPECT_EQ(dir.entries(), 1);
  {
    OutputTransaction tx;
    ASSERT_TRUE(write_bytes_atomically(a, "new a").ok());
    ASSERT_TRUE(write_bytes_atomically(dir.file("b.json"), "b").ok());
    ASSERT_TRUE(tx.commit().ok());
  }
  EXPECT_EQ(slurp(a), "new a");
  EXPECT_EQ(slurp(dir.file("b.json")), "b");
  EXPECT_EQ(dir.entries(), 2);
}

// OutputTransaction::Writer: another thread's writes are staged in the transaction (not renamed
// into place, and not in a transaction of that thread's own), committed or discarded with it; the
// thread's own state is restored when the Writer ends.
TEST(AtomicFile, AWriterThreadStagesInTheTransaction) {
  test::TempDir dir;
  const std::string a = dir.write("a.ply", "old a");
  for (const bool commit : {false, true}) {
    OutputTransaction tx;
    Status written, after;
    std::thread writer([&] {
      {
        const OutputTransaction::Writer staged(tx);
        written = write_bytes_atomically(a, "new a");
      }
      // Without the Writer, this thread writes straight through again.
      after = write_bytes_atomically(dir.file("own.txt"), "own");
    });
    writer.join();
    ASSERT_TRUE(written.ok());
    ASSERT_TRUE(after.ok());
    EXPECT_EQ(slurp(dir.file("own.txt")), "own");
    EXPECT_EQ(slurp(a), "old a");  // staged, not yet in place
    EXPECT_FALSE(tx.staged_file(a).empty());
    EXPECT_EQ(slurp(tx.staged_file(a)), "new a");
    if (commit) {
      ASSERT_TRUE(tx.commit().ok());
    }
    std::filesystem::remove(dir.file("own.txt"));
    if (!commit) {
      const std::string staged = tx.staged_file(a);
      // Destroyed uncommitted below: the file stays as it was, the temporary goes.
      EXPECT_TRUE(std::filesystem::exists(staged));
    }
  }
  EXPECT_EQ(slurp(a), "new a");
  EXPECT_EQ(dir.entries(), 1);
}

TEST(AtomicFile, TransactionRefusesOneFileNamedTwice) {
  test::TempDir dir;
  const std::string a = dir.write("same.ply", "old");
  OutputTransaction tx;
  ASSERT_TRUE(write_bytes_atomically(a, "volume").ok());
  const Status s = write_bytes_atomically(dir.path() + "/./same.ply", "{json}");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("another output of this run"), std::string::npos)
      << s.error().message;
}

TEST(AtomicFile, FailedCommitPutsBackWhatItReplaced) {
  test::TempDir dir;
  const std::string a = dir.write("a.ply", "old a");
  const std::string b = dir.file("b.json");
  {
    OutputTransaction tx;
    ASSERT_TRUE(write_bytes_atomically(a, "new a").ok());
    ASSERT_TRUE(write_bytes_atomically(b, "new b").ok());
    // Between staging and commit, b's name becomes a non-empty directory: its rename fails.
    ASSERT_EQ(::mkdir(b.c_str(), 0700), 0);
    dir.write("b.json/inside", "x");
    const Status s = tx.commit();
    ASSERT_FALSE(s.ok());
    EXPECT_NE(s.error().message.find("no output written"), std::string::npos) << s.error().message;
  }
  EXPECT_EQ(slurp(a), "old a");
  EXPECT_TRUE(std::filesystem::is_directory(b));
  EXPECT_EQ(dir.entries(), 2);
}

}  // namespace
}  // namespace lightvol
