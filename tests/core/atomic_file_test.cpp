#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include <lightvol/core/atomic_file.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

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

TEST(AtomicFile, DeviceOrPipeTargetIsRefusedAndKept) {
  // Renaming over a FIFO (or /dev/stdout) would replace it with a plain file.
  test::TempDir dir;
  const std::string fifo = dir.file("pipe.ply");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const Status s = write_bytes_atomically(fifo, "x");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("is not a regular file"), std::string::npos)
      << s.error().message;
  EXPECT_TRUE(std::filesystem::is_fifo(fifo));
}

}  // namespace
}  // namespace lightvol
