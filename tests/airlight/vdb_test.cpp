// OpenVDB densities (`"density": {"type": "vdb", ...}`): the grid read through lightvol-image in
// its own transform, sampled trilinearly; every bad file refused with one line naming it. The
// files are written at test time by tests/airlight/make_vdbs.py (OpenVDB's Python module).
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>

#include <gtest/gtest.h>

#include <lightvol/airlight/airlight.h>
#include <lightvol/airlight/heterogeneous.h>
#include <lightvol/core/limits.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

// make_vdbs.py's sphere of smoke, at a world point.
constexpr double kRadius = 1.3, kVoxel = 0.1;
const Vec3d kCentre{0.4, 0.8, 0.3};
double sphere_density(const Vec3d& x) {
  const Vec3d d = x - kCentre;
  const double r2 = dot(d, d) / (kRadius * kRadius);
  if (r2 >= 1) return 0;
  return 4.0 * (1 - r2) * (1 - r2) * (1 + 0.4 * std::sin(3 * x.x) * std::sin(2 * x.z));
}
// Index (i, j, k) of the sphere's grid in the world: voxels of 0.1 turned 30° about y.
Vec3d sphere_voxel(double i, double j, double k) {
  const double c = std::cos(std::numbers::pi / 6), s = std::sin(std::numbers::pi / 6);
  return kCentre + kVoxel * Vec3d{c * i + s * k, j, -s * i + c * k};
}

std::string medium_json(const std::string& file, const std::string& extra = "") {
  return R"({"scattering": 0.1, "density": {"type": "vdb", "file": ")" + file + "\"" + extra + "}}";
}

Result<Medium> load(const std::string& folder, const std::string& file,
                    const std::string& extra = "") {
  return parse_medium(medium_json(file, extra), folder + "/m.json");
}

TEST(VdbDensity, TheGridIsSampledTrilinearlyInItsOwnTransform) {
  REQUIRE_TEST_VDBS(folder);
  Result<Medium> m = load(folder, "sphere.vdb");
  ASSERT_TRUE(m) << m.error().message;
  const Density& d = m->density;
  ASSERT_EQ(d.type, DensityType::grid);
  ASSERT_TRUE(d.varying());
  const VoxelGrid& g = *d.grid;
  EXPECT_EQ(g.source, folder + "/sphere.vdb: grid 'density'");
  EXPECT_EQ(g.background, 0.0);
  EXPECT_NEAR(d.finest_wavelength(), kVoxel, 1e-12);
  // The active box: the voxels within the sphere, at most 13 from the centre on each axis.
  for (int a = 0; a < 3; ++a) {
    EXPECT_GE(g.origin[a], -13);
    EXPECT_LE(g.origin[a] + g.dims[a], 14);
    EXPECT_GE(g.dims[a], 24);
  }
  // At voxel centres, the value written (a float); between them, the trilinear blend.
  double worst = 0;
  int inside = 0;
  for (int i = -12; i <= 12; i += 3)
    for (int j = -12; j <= 12; j += 2)
      for (int k = -12; k <= 12; k += 3) {
        const Vec3d x = sphere_voxel(i, j, k);
        worst = std::max(worst, std::abs(d(x) - sphere_density(x)));
        inside += sphere_density(x) > 0;
        const double blend = 0.25 * (sphere_density(sphere_voxel(i, j, k)) +
                                     sphere_density(sphere_voxel(i + 1, j, k))) +
                             0.25 * (sphere_density(sphere_voxel(i, j + 1, k)) +
                                     sphere_density(sphere_voxel(i + 1, j + 1, k)));
        EXPECT_NEAR(d(sphere_voxel(i + 0.5, j + 0.5, k)), blend, 1e-5) << i << " " << j << " " << k;
      }
  EXPECT_GT(inside, 100);
  EXPECT_LT(worst, 1e-5);  // float storage of values up to 5.6
  EXPECT_NEAR(d.max_density(), 5.05, 0.05);
  // Far outside: the background.
  EXPECT_EQ(d({40, -7, 3}), 0.0);
  EXPECT_EQ(d(sphere_voxel(14.5, 0, 0)), 0.0);
  // The part of a line within a voxel of the box: a ray along the sphere's local x through its
  // centre enters at index −13.x and leaves at +13.x.
  double t0 = 0, t1 = 0;
  const Vec3d along = sphere_voxel(1, 0, 0) - kCentre;
  ASSERT_TRUE(g.clip(kCentre, along, -100, 100, &t0, &t1));
  EXPECT_NEAR(t0, g.origin[0] - 1.0, 1e-9);
  EXPECT_NEAR(t1, g.origin[0] + g.dims[0] * 1.0, 1e-9);
  EXPECT_FALSE(g.clip({10, 10, 10}, {0, 1, 0}, 0, 100, &t0, &t1));
  // A second grid by name; "scale" multiplies the values.
  Result<Medium> t = load(folder, "sphere.vdb", R"(, "grid": "temperature", "scale": 0.5)");
  ASSERT_TRUE(t) << t.error().message;
  EXPECT_EQ(t->density.grid->values.size(), 1u);
  EXPECT_EQ(t->density.grid->values[0], 150.0f);
}

// A grid of background 1 and active voxels of 1 is the homogeneous medium, and so is the
// reference's airlight through it.
TEST(VdbDensity, AConstantGridIsTheHomogeneousMedium) {
  REQUIRE_TEST_VDBS(folder);
  Result<Medium> m = load(folder, "constant.vdb");
  ASSERT_TRUE(m) << m.error().message;
  EXPECT_EQ(m->density.grid->background, 1.0);
  for (const Vec3d& x : {Vec3d{0.1, 0.2, 0.3}, Vec3d{0.5, 0.5, 0.5}, Vec3d{-30, 4, 12}})
    EXPECT_EQ(m->density(x), 1.0);
}

// Each bad file: one line naming the file (and the grid), what is wrong.
TEST(VdbDensity, BadFilesAreRefusedWithOneLineNamingThem) {
  REQUIRE_TEST_VDBS(folder);
  const test::TempDir dir;
  const std::string sphere = test::slurp(folder + "/sphere.vdb");
  ASSERT_GT(sphere.size(), 1000u);
  std::ofstream(dir.file("truncated.vdb"), std::ios::binary) << sphere.substr(0, sphere.size() / 2);
  std::string corrupt = sphere;
  for (std::size_t i = 64; i < corrupt.size(); i += 7) corrupt[i] = static_cast<char>(i * 131);
  std::ofstream(dir.file("corrupt.vdb"), std::ios::binary) << corrupt;
  std::ofstream(dir.file("text.vdb"), std::ios::binary) << "not a grid\n";
  std::ofstream(dir.file("magic.vdb"), std::ios::binary) << std::string(" BDV", 4);
  std::ofstream(dir.file("header.vdb"), std::ios::binary) << sphere.substr(0, 56);
  std::ofstream(dir.file("wide.vdb"), std::ios::binary) << std::string(" BDV\x01\0\0\0", 8);
  std::filesystem::create_directory(dir.file("folder.vdb"));
  for (const std::string name : {"sphere.vdb", "vec3.vdb", "huge.vdb"})
    std::filesystem::copy_file(folder + "/" + name, dir.file(name));
  for (const std::string name : {"negative.vdb", "nan.vdb", "bool.vdb", "empty.vdb"})
    std::filesystem::copy_file(folder + "/" + name, dir.file(name));
  const std::string at = dir.path() + "/";
  const std::pair<std::string, std::string> cases[] = {
      {"missing.vdb", at + "missing.vdb: no such file"},
      {"folder.vdb", at + "folder.vdb: is a directory, not an OpenVDB file"},
      {"text.vdb", at + "text.vdb: not an OpenVDB file"},
      // OpenVDB would read its header past the end of these (its verdict changed from run to run).
      {"magic.vdb", at + "magic.vdb: a truncated OpenVDB file (4 bytes, shorter than OpenVDB's "
                         "57-byte header)"},
      {"header.vdb", at + "header.vdb: a truncated OpenVDB file (56 bytes, shorter than "
                          "OpenVDB's 57-byte header)"},
      {"wide.vdb", at + "wide.vdb: not an OpenVDB file (it does not start with OpenVDB's magic "
                        "number)"},
      {"truncated.vdb", at + "truncated.vdb: "},
      {"corrupt.vdb", at + "corrupt.vdb: "},
      {R"(sphere.vdb", "grid": "smoke)",
       at + "sphere.vdb: has no grid named 'smoke' (its grids: 'density', 'temperature')"},
      {"vec3.vdb", at + "vec3.vdb: grid 'density': holds vec3s values; a density grid holds "
                        "scalars (float or double)"},
      {"bool.vdb", at + "bool.vdb: grid 'density': holds bool values"},
      {"huge.vdb", at + "huge.vdb: grid 'density': its 8192x8192x8192 voxels (dense floats, here "
                        "and on the GPU) needs about 4.0 TiB of memory, more than the budget"},
      {"negative.vdb", at + "negative.vdb: grid 'density': the voxel at index (2, 3, 4) is "
                            "negative (-0.5); densities are finite and >= 0"},
      {"nan.vdb", at + "nan.vdb: grid 'density': the voxel at index (2, 3, 4) is NaN"},
      {"empty.vdb", at + "empty.vdb: grid 'density': has no active voxels (an empty grid)"},
  };
  for (const auto& [file, expected] : cases) {
    Result<Medium> m = parse_medium(medium_json(file), dir.file("m.json"));
    ASSERT_FALSE(m) << file;
    const std::string& message = m.error().message;
    // The medium's file and key, then the grid's file and what is wrong with it.
    EXPECT_EQ(message.rfind(dir.file("m.json") + ": key 'density.file': " + expected, 0), 0u)
        << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    EXPECT_LT(message.size(), 400u) << message;
    std::printf("  %s\n", message.c_str());
  }
  // Within a smaller budget the sphere itself is too big (2 · 4 bytes per voxel).
  const std::uint64_t budget = memory_budget();
  set_memory_budget(100000);
  Result<Medium> small = parse_medium(medium_json("sphere.vdb"), dir.file("m.json"));
  set_memory_budget(budget);
  ASSERT_FALSE(small);
  EXPECT_NE(small.error().message.find("more than the budget"), std::string::npos)
      << small.error().message;
  // The server that refused is still the one that serves the next request.
  EXPECT_TRUE(parse_medium(medium_json("sphere.vdb"), dir.file("m.json")));
}

}  // namespace
}  // namespace lightvol
