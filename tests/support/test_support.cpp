#include "support/test_support.h"

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <thread>
#include <vector>

namespace lightvol::test {
namespace fs = std::filesystem;

TempDir::TempDir() {
  std::string pattern = (fs::temp_directory_path() / "lightvol-test-XXXXXX").string();
  char* made = ::mkdtemp(pattern.data());
  if (!made) std::abort();
  path_ = made;
}

TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

std::string TempDir::write(const std::string& name, const std::string& text) const {
  const std::string p = file(name);
  std::ofstream(p, std::ios::binary) << text;
  return p;
}

int TempDir::entries() const {
  int n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(path_)) ++n;
  return n;
}

DepthImage make_depth(int width, int height, const std::function<float(int, int)>& value) {
  DepthImage image;
  image.width = width;
  image.height = height;
  image.values.resize(static_cast<std::size_t>(width) * height);
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c)
      image.values[static_cast<std::size_t>(r) * width + c] = value(c, r);
  return image;
}

DepthImage constant_depth(int width, int height, float value) {
  return make_depth(width, height, [value](int, int) { return value; });
}

Light light_from_json(const std::string& json) {
  Result<Light> light = parse_light(json, "test.json");
  if (!light) {
    ADD_FAILURE() << light.error().message;
    return {};
  }
  return *light;
}

std::string spot_json(const std::string& depth, double aspect) {
  std::ostringstream s;
  s << R"({"type": "spot", "position": [0, 4, 0], "direction": [0, -1, 0], "up": [0, 0, -1],)"
    << R"( "fov_y_deg": 60, "aspect": )" << aspect << R"(, "near": 0.1, "far": 30, "depth": ")"
    << depth << "\"}";
  return s.str();
}

std::string directional_json(const std::string& depth) {
  return R"({"type": "directional", "position": [0, 4, 0], "direction": [0, -1, 0], "up": [0, 0, -1],)"
         R"( "ortho": [-5, 5, -4, 4], "near": 0, "far": 10, "depth": ")" +
         depth + "\"}";
}

::testing::AssertionResult is_closed_and_oriented(const Mesh& mesh) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
    const auto tri = mesh.triangle(t);
    for (int k = 0; k < 3; ++k) {
      if (tri[k] >= mesh.num_vertices())
        return ::testing::AssertionFailure() << "face " << t << " indexes vertex " << tri[k];
      ++directed[{tri[k], tri[(k + 1) % 3]}];
    }
  }
  for (const auto& [edge, count] : directed) {
    if (count != 1)
      return ::testing::AssertionFailure() << "directed edge " << edge.first << "->" << edge.second
                                           << " used " << count << " times";
    const auto rev = directed.find({edge.second, edge.first});
    if (rev == directed.end() || rev->second != 1)
      return ::testing::AssertionFailure()
             << "edge " << edge.first << "->" << edge.second << " has no opposite half";
  }
  return ::testing::AssertionSuccess();
}

::testing::AssertionResult has_no_degenerate_triangles(const Mesh& mesh) {
  for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
    const auto [a, b, c] = mesh.triangle(t);
    if (a == b || b == c || a == c)
      return ::testing::AssertionFailure() << "face " << t << " collapsed";
    const auto pa = mesh.vertex(a), pb = mesh.vertex(b), pc = mesh.vertex(c);
    const double u[3] = {double(pb[0]) - pa[0], double(pb[1]) - pa[1], double(pb[2]) - pa[2]};
    const double v[3] = {double(pc[0]) - pa[0], double(pc[1]) - pa[1], double(pc[2]) - pa[2]};
    const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                         u[0] * v[1] - u[1] * v[0]};
    if (n[0] == 0 && n[1] == 0 && n[2] == 0)
      return ::testing::AssertionFailure() << "face " << t << " has zero area";
  }
  return ::testing::AssertionSuccess();
}

CommandResult run_lightvol(const std::string& args) {
#ifndef LIGHTVOL_EXE
  ADD_FAILURE() << "built without the lightvol executable";
  return {};
#else
  TempDir io;
  const std::string out = io.file("stdout"), err = io.file("stderr");
  const std::string command =
      std::string("'") + LIGHTVOL_EXE + "' " + args + " >'" + out + "' 2>'" + err + "' </dev/null";
  const int status = std::system(command.c_str());
  CommandResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  std::ifstream o(out), e(err);
  std::stringstream so, se;
  so << o.rdbuf();
  se << e.rdbuf();
  r.out = so.str();
  r.err = se.str();
  return r;
#endif
}

std::string test_vdb_folder() {
  static TempDir* const folder = new TempDir;  // kept to the end of the process
  static const std::string made = [] {
    std::vector<std::string> pythons = {"/usr/bin/python3", "python3"};
    if (const char* env = std::getenv("LIGHTVOL_TEST_PYTHON"); env && *env)
      pythons.insert(pythons.begin(), env);
    for (const std::string& python : pythons) {
      const std::string command =
          q(python) + " " + q(std::string(LIGHTVOL_SOURCE_DIR) + "/tests/airlight/make_vdbs.py") +
          " " + q(folder->path()) + " >/dev/null 2>&1";
      if (std::system(command.c_str()) == 0) return folder->path();
    }
    return std::string();
  }();
  return made;
}

std::string q(const std::string& text) {
  std::string quoted = "'";
  for (const char ch : text) quoted += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
  return quoted + "'";
}

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

bool process_dies(int pid) {
  for (int i = 0; i < 6000; ++i) {
    const std::string stat = slurp("/proc/" + std::to_string(pid) + "/stat");
    const std::size_t close = stat.rfind(')');  // the state follows the command name
    if (stat.empty() || (close != std::string::npos && close + 2 < stat.size() &&
                         (stat[close + 2] == 'Z' || stat[close + 2] == 'X')))
      return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

std::string fuzz_regression_file(const std::string& target, const std::string& name) {
  const std::string path =
      std::string(LIGHTVOL_SOURCE_DIR) + "/tests/fuzz/corpus/" + target + "/" + name;
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_GT(bytes.size(), 1u) << path;
  return bytes.empty() ? bytes : bytes.substr(1);
}

}  // namespace lightvol::test
