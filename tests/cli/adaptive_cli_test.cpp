// `lightvol build --adaptive` and `lightvol stats` as a user runs them: the counts stats reports
// are the counts build writes, the bound is met, bad flag combinations are one-line errors.
#include <algorithm>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <lightvol/depth/depth_image.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

using test::q;
using test::slurp;

// A 65×49 map (floor, a box, a one-texel bar) and a spot and a directional light, linear depth.
struct Workspace {
  test::TempDir dir;
  std::string depth, spot, directional;
  Workspace() {
    depth = dir.file("depth.exr");
    const DepthImage d = test::make_depth(65, 49, [](int c, int r) {
      if (c == 40) return 5.0f;
      if (c > 10 && c < 30 && r > 5 && r < 20) return 4.0f;
      return static_cast<float>(8.0 + 0.01 * c);
    });
    EXPECT_TRUE(write_depth_image(depth, d).ok());
    spot = dir.write("spot.json", test::spot_json("linear"));
    directional = dir.write("dir.json", test::directional_json("linear"));
  }
};

void expect_input_error(const test::CommandResult& r, const std::string& needle) {
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err.rfind("lightvol: ", 0), 0u) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find(needle), std::string::npos) << r.err;
}

// The face count in a PLY header.
long ply_faces(const std::string& path) {
  const std::string text = slurp(path);
  const std::size_t at = text.find("element face ");
  if (at == std::string::npos) return -1;
  return std::stol(text.substr(at + 13));
}

TEST(AdaptiveCli, StatsCountsAreWhatBuildWrites) {
  Workspace w;
  for (const std::string& light : {w.spot, w.directional}) {
    const test::CommandResult s = test::run_lightvol("stats " + q(w.depth) + " --light " +
                                                     q(light) + " --max-error 0.001,0.05,1 --json");
    ASSERT_EQ(s.exit_code, 0) << s.err;
    const nlohmann::json stats = nlohmann::json::parse(s.out);
    EXPECT_EQ(stats["static"]["triangles"], light == w.spot ? 2 * 64 * 48 + 2 * 64 + 2 * 48
                                                            : 2 * 64 * 48 + 3 * (2 * 64 + 2 * 48));
    // Both tessellations (collapse first), each at the three bounds.
    ASSERT_EQ(stats["adaptive"].size(), 6u);
    std::uint64_t previous = ~std::uint64_t{0};
    for (std::size_t i = 0; i < 6; ++i) {
      const auto& row = stats["adaptive"][i];
      const std::string t = row["tessellation"].get<std::string>();
      EXPECT_EQ(t, i < 3 ? "collapse" : "quadtree");
      if (i == 3) previous = ~std::uint64_t{0};
      const double e = row["max_error"].get<double>();
      const std::string out = w.dir.file("v.ply"), report = w.dir.file("r.json");
      const test::CommandResult b =
          test::run_lightvol("build " + q(w.depth) + " --light " + q(light) +
                             " --adaptive --max-error " + std::to_string(e) + " --tessellation " +
                             t + " --out " + q(out) + " --report " + q(report) + " --quiet");
      ASSERT_EQ(b.exit_code, 0) << b.err;
      const nlohmann::json r = nlohmann::json::parse(slurp(report));
      EXPECT_EQ(r["mode"], "adaptive");
      EXPECT_EQ(r["triangles"], row["triangles"]);
      EXPECT_EQ(r["vertices"], row["vertices"]);
      EXPECT_EQ(ply_faces(out), row["triangles"].get<long>());
      EXPECT_LE(row["max_error_reached"].get<double>(), e);
      EXPECT_EQ(r["adaptive"]["max_error_reached"], row["max_error_reached"]);
      EXPECT_EQ(r["adaptive"]["tessellation"], t);
      EXPECT_EQ(r["adaptive"]["min_angle_degrees"], row["min_angle_degrees"]);
      EXPECT_GT(row["min_angle_degrees"].get<double>(), 0);
      EXPECT_GE(row["min_area_texels"].get<double>(), 0.5);
      EXPECT_GT(r["volume"].get<double>(), 0);
      // The quadtree's cells only merge as the bound grows (a greedy collapse promises no such
      // monotony).
      if (t == "quadtree") {
        EXPECT_LE(row["triangles"].get<std::uint64_t>(), previous);
      }
      previous = row["triangles"].get<std::uint64_t>();
    }
  }
}

TEST(AdaptiveCli, BothTessellationsPassCheckWithTheLight) {
  Workspace w;
  for (const std::string& light : {w.spot, w.directional})
    for (const std::string t : {"collapse", "quadtree"}) {
      SCOPED_TRACE(light + " " + t);
      const std::string out = w.dir.file("v.ply");
      const test::CommandResult b =
          test::run_lightvol("build " + q(w.depth) + " --light " + q(light) +
                             " --adaptive --max-error 0.001 --tessellation " + t + " --out " +
                             q(out) + " --quiet --no-check");
      ASSERT_EQ(b.exit_code, 0) << b.err;
      const test::CommandResult check =
          test::run_lightvol("check " + q(out) + " --light " + q(light));
      EXPECT_EQ(check.exit_code, 0) << check.out << check.err;
    }
}

TEST(AdaptiveCli, CsvAndTableFormats) {
  Workspace w;
  const test::CommandResult csv = test::run_lightvol("stats " + q(w.depth) + " --light " +
                                                     q(w.directional) + " --max-error 0.01 --csv");
  ASSERT_EQ(csv.exit_code, 0) << csv.err;
  EXPECT_EQ(csv.out.rfind("mode,max_error,triangles,vertices,max_error_reached,", 0), 0u)
      << csv.out;
  EXPECT_EQ(std::count(csv.out.begin(), csv.out.end(), '\n'), 4) << csv.out;
  EXPECT_NE(csv.out.find("\nstatic,,"), std::string::npos);
  EXPECT_NE(csv.out.find("\nadaptive,0.01,"), std::string::npos);
  EXPECT_NE(csv.out.find(",collapse,"), std::string::npos);
  EXPECT_NE(csv.out.find(",quadtree,"), std::string::npos);
  const test::CommandResult table = test::run_lightvol(
      "stats " + q(w.depth) + " --light " + q(w.directional) + " --max-error 0.01 --quiet");
  ASSERT_EQ(table.exit_code, 0) << table.err;
  EXPECT_NE(table.out.find("static grid: 6,816 triangles"), std::string::npos) << table.out;
}

TEST(AdaptiveCli, LaplacianBuildIsValid) {
  Workspace w;
  const std::string out = w.dir.file("l.ply"), report = w.dir.file("l.json");
  const test::CommandResult b = test::run_lightvol("build " + q(w.depth) + " --light " + q(w.spot) +
                                                   " --refine laplacian --threshold 0.001 --out " +
                                                   q(out) + " --report " + q(report) + " --quiet");
  ASSERT_EQ(b.exit_code, 0) << b.err;
  const nlohmann::json r = nlohmann::json::parse(slurp(report));
  EXPECT_EQ(r["adaptive"]["refine"], "laplacian");
  EXPECT_LT(r["triangles"].get<int>(), 2 * 64 * 48 + 2 * 64 + 2 * 48);
  EXPECT_GT(r["volume"].get<double>(), 0);
}

TEST(AdaptiveCli, BadFlagCombinationsAreErrors) {
  Workspace w;
  const std::string base =
      "build " + q(w.depth) + " --light " + q(w.spot) + " --out " + q(w.dir.file("x.ply")) + " ";
  expect_input_error(test::run_lightvol(base + "--adaptive"), "--adaptive: needs --max-error");
  expect_input_error(test::run_lightvol(base + "--max-error 0.1"),
                     "--max-error: applies with --adaptive only");
  expect_input_error(test::run_lightvol(base + "--refine laplacian"),
                     "--refine laplacian: needs --threshold");
  expect_input_error(test::run_lightvol(base + "--adaptive --max-error 0.1 --threshold 2"),
                     "--threshold: applies with --refine laplacian only");
  expect_input_error(test::run_lightvol(base + "--adaptive --max-error -1"), "--max-error");
  expect_input_error(test::run_lightvol(base + "--tessellation quadtree"),
                     "--tessellation: applies with --adaptive only");
  expect_input_error(
      test::run_lightvol(base + "--refine laplacian --threshold 1 --tessellation collapse"),
      "--tessellation collapse: needs a bound");
  expect_input_error(test::run_lightvol(base + "--adaptive --max-error 0.1 --tessellation rtin"),
                     "--tessellation");
  expect_input_error(test::run_lightvol("stats " + q(w.depth) + " --light " + q(w.spot) +
                                        " --tessellation collapse,rtin"),
                     "--tessellation: 'rtin' is not collapse or quadtree");
  EXPECT_FALSE(std::ifstream(w.dir.file("x.ply")).good());
  expect_input_error(
      test::run_lightvol("stats " + q(w.depth) + " --light " + q(w.spot) + " --max-error 0.1,abc"),
      "--max-error: 'abc' is not a non-negative number");
  expect_input_error(
      test::run_lightvol("stats " + q(w.depth) + " --light " + q(w.spot) + " --json --csv"),
      "--json and --csv");
}

}  // namespace
}  // namespace lightvol
