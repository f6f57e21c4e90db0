// Shared test fixtures: temporary directories, synthetic depth maps, lights, and mesh properties
// checked edge by edge.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include <gtest/gtest.h>

#include <lightvol/core/mesh.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/light/light.h>

namespace lightvol::test {

// A fresh directory under the system temp dir, removed with everything in it on destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::string& path() const { return path_; }
  std::string file(const std::string& name) const { return path_ + "/" + name; }
  // Writes `text` to `name` in this directory and returns its path.
  std::string write(const std::string& name, const std::string& text) const;
  // Number of entries in the directory (to assert that nothing, not even a temporary, was left).
  int entries() const;

 private:
  std::string path_;
};

// A W×H depth image whose texel (col, row) holds value(col, row).
DepthImage make_depth(int width, int height, const std::function<float(int col, int row)>& value);
DepthImage constant_depth(int width, int height, float value);

// Lights parsed from JSON text (the test fails on a parse error).
Light light_from_json(const std::string& json);
// A spot light at (0, 4, 0) looking down −Y, up −Z, fov 60°, near 0.1, far 30, `depth` encoding.
std::string spot_json(const std::string& depth = "window", double aspect = 1.0);
// A directional light centred at (0, 4, 0) looking down −Y, ortho [−5, 5, −4, 4], near 0, far 10.
std::string directional_json(const std::string& depth = "window");

// Edge-by-edge: every undirected edge used by exactly two triangles in opposite directions.
::testing::AssertionResult is_closed_and_oriented(const Mesh& mesh);
// No triangle with repeated vertices or zero area (in double precision).
::testing::AssertionResult has_no_degenerate_triangles(const Mesh& mesh);

// Path of the lightvol executable; runs it with `args` (a shell-quoted string), capturing
// stdout and stderr. Returns the exit code.
struct CommandResult {
  int exit_code = -1;
  std::string out, err;
};
CommandResult run_lightvol(const std::string& args);

// `text` quoted for the shell (single quotes; a quote inside becomes '\'').
std::string q(const std::string& text);
// The whole file at `path`, byte for byte ("" if it cannot be read).
std::string slurp(const std::string& path);

// Whether the process `pid` (not a child of the caller) has ended, or ends within a minute (it
// may be a zombie its new parent has not reaped yet): checked every 10 ms, so a process that was
// killed passes at once and one that lives on fails after the minute.
bool process_dies(int pid);

// The folder of the density tests' OpenVDB files (tests/airlight/make_vdbs.py lists them), written
// once per test process by that script with a Python that has OpenVDB's module (Debian's
// python3-openvdb): $LIGHTVOL_TEST_PYTHON, /usr/bin/python3 or python3. "" when none has it (the
// caller skips, saying so).
std::string test_vdb_folder();
#define REQUIRE_TEST_VDBS(folder)                                                             \
  const std::string folder = ::lightvol::test::test_vdb_folder();                             \
  if (folder.empty())                                                                         \
  GTEST_SKIP() << "no Python with OpenVDB's module (pyopenvdb: Debian's python3-openvdb) to " \
                  "write the test's OpenVDB files"

// The file a fuzz target read from regression input tests/fuzz/corpus/TARGET/NAME: the input
// without its first byte, which the depth_image and mesh targets spend on choosing the extension.
std::string fuzz_regression_file(const std::string& target, const std::string& name);

}  // namespace lightvol::test
