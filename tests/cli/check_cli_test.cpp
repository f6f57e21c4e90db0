// lightvol check and build --check, end to end: exit codes, reports, what build writes passing
// check.
#include <string>
#include <utility>

#include <gtest/gtest.h>

#include <lightvol/check/check.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/export/export.h>
#include <lightvol/volume/static_volume.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

using test::TempDir;

// A 9×7 spot map: floor at window depth 0.98 (≈ 4.3 below the light) with a 3×3 occluder at
// 0.95 (≈ 1.9 below it).
DepthImage occluded_depth() {
  return test::make_depth(
      9, 7, [](int c, int r) { return (c >= 3 && c <= 5 && r >= 2 && r <= 4) ? 0.95f : 0.98f; });
}

Mesh sound_spot_volume() {
  Result<Mesh> mesh = build_static_volume(test::light_from_json(test::spot_json()),
                                          occluded_depth(), {}, "test.exr");
  EXPECT_TRUE(mesh.ok());
  return *mesh;
}

TEST(CheckCommand, ExitCodesAndReports) {
  TempDir dir;
  const std::string light = dir.write("light.json", test::spot_json());
  const Mesh sound = sound_spot_volume();
  ASSERT_TRUE(write_mesh(dir.file("sound.ply"), sound).ok());
  Mesh flipped = sound;
  std::swap(flipped.indices[4], flipped.indices[5]);
  ASSERT_TRUE(write_mesh(dir.file("flipped.obj"), flipped).ok());

  auto r = test::run_lightvol("check '" + dir.file("sound.ply") + "' --light '" + light + "'");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("valid"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("non-self-nesting"), std::string::npos) << r.out;

  r = test::run_lightvol("check '" + dir.file("sound.ply") + "' --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("\"valid\": true"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("CGAL"), std::string::npos) << r.out;

  r = test::run_lightvol("check '" + dir.file("flipped.obj") + "' --light '" + light + "' --json");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.out.find("\"valid\": false"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"first_failure\": \"oriented"), std::string::npos) << r.out;

  r = test::run_lightvol("check '" + dir.file("flipped.obj") + "' --quiet");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.out, "");
  EXPECT_NE(r.err.find("oriented"), std::string::npos) << r.err;

  // Unreadable input and bad usage: 2, with the file named.
  const std::string junk = dir.write("junk.ply", "this is not a mesh\n");
  r = test::run_lightvol("check '" + junk + "'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("junk.ply"), std::string::npos) << r.err;
  r = test::run_lightvol("check '" + dir.file("missing.ply") + "'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("missing.ply: no such file"), std::string::npos) << r.err;
  r = test::run_lightvol("check '" + dir.file("sound.ply") + "' --light '" +
                         dir.file("nolight.json") + "'");
  EXPECT_EQ(r.exit_code, 2);
  r = test::run_lightvol("check");
  EXPECT_EQ(r.exit_code, 2);
}

// A folded volume stays invalid in a file that also holds a far vertex no face uses: the proof's
// tolerance is each face's own (issue: one vertex at 10^7 made `check --light` say valid).
TEST(CheckCommand, AnUnusedFarVertexDoesNotMakeAFoldedVolumeValid) {
  TempDir dir;
  const std::string light = dir.write("light.json", test::spot_json());
  Mesh folded = sound_spot_volume();
  // Border vertex (8, 3) lifted above the light, through its neighbours.
  folded.positions[3 * (3 * 9 + 8) + 1] = 5;
  ASSERT_TRUE(write_mesh(dir.file("folded.ply"), folded).ok());
  auto r = test::run_lightvol("check '" + dir.file("folded.ply") + "' --light '" + light + "'");
  ASSERT_EQ(r.exit_code, 1) << r.out << r.err;
  for (const float far : {1e6f, 1e7f, 3.4e38f}) {
    Mesh with_far = folded;
    with_far.positions.insert(with_far.positions.end(), {0, far, 0});
    ASSERT_TRUE(write_mesh(dir.file("far.ply"), with_far).ok());
    r = test::run_lightvol("check '" + dir.file("far.ply") + "' --light '" + light + "' --quiet");
    EXPECT_EQ(r.exit_code, 1) << far << ": " << r.err;
    EXPECT_NE(r.err.find("non-self-nesting"), std::string::npos) << r.err;
  }
}

// A mesh is measured against --max-memory before it is read: the check's estimate from the file's
// counts (check_memory_bytes), at the byte. Before, `check` of a 1 M-triangle PLY under
// --max-memory 1M used 256 MB.
TEST(CheckCommand, MeshesAreMeasuredAgainstTheBudgetAtTheBoundary) {
  TempDir dir;
  const std::string light = dir.write("light.json", test::spot_json());
  const Mesh sound = sound_spot_volume();
  const std::string path = dir.file("sound.ply");
  ASSERT_TRUE(write_mesh(path, sound).ok());
  struct Mode {
    std::string flags;
    bool with_light;
    CheckEngine engine;
  };
  for (const Mode& m : {Mode{"", false, CheckEngine::lightvol},
                        Mode{" --light " + test::q(light), true, CheckEngine::lightvol},
                        Mode{" --engine cgal", false, CheckEngine::cgal}}) {
    CheckOptions options;
    options.engine = m.engine;
    const std::uint64_t needed =
        check_memory_bytes(sound.num_vertices(), sound.num_triangles(), m.with_light, options);
    const std::string check = "check " + test::q(path) + m.flags + " --quiet --max-memory ";
    auto r = test::run_lightvol(check + std::to_string(needed));
    EXPECT_EQ(r.exit_code, 0) << m.flags << ": " << r.err;
    r = test::run_lightvol(check + std::to_string(needed - 1));
    EXPECT_EQ(r.exit_code, 2) << m.flags;
    EXPECT_EQ(r.err.rfind("lightvol: " + path + ": checking " +
                              std::to_string(sound.num_triangles()) + " triangles needs about ",
                          0),
              0u)
        << r.err;
    EXPECT_NE(r.err.find("of memory, more than the budget of"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("raise it with --max-memory"), std::string::npos) << r.err;
  }
  // The estimate grows with the counts: 12 MiB, 24 bytes a vertex, 12/64/256 bytes a triangle.
  CheckOptions cgal;
  cgal.engine = CheckEngine::cgal;
  EXPECT_EQ(check_memory_bytes(500000, 1000000, true), (12u << 20) + 24 * 500000u + 12 * 1000000u);
  EXPECT_EQ(check_memory_bytes(500000, 1000000, false), (12u << 20) + 24 * 500000u + 64 * 1000000u);
  EXPECT_EQ(check_memory_bytes(500000, 1000000, false, cgal),
            (12u << 20) + 24 * 500000u + 256 * 1000000u);
}

// A mesh whose header promises more than the budget holds is refused before it is read, in any
// command that reads meshes (here: 3 M faces in the header of a file that holds them).
TEST(CheckCommand, AMeshOverTheBudgetIsRefusedFromItsHeaderCounts) {
  TempDir dir;
  std::string ply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nelement face 3000000\n"
      "property list uchar int vertex_indices\nend_header\n";
  ply += std::string(36, '\0');
  std::string face(13, '\0');
  face[0] = 3;
  face[5] = 1;
  face[9] = 2;
  for (int f = 0; f < 3000000; ++f) ply += face;
  const std::string path = dir.write("big.ply", ply);
  const auto r = test::run_lightvol("check " + test::q(path) + " --quiet --max-memory 64M");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err,
            "lightvol: " + path +
                ": checking 3000000 triangles needs about 195.1 MiB of memory, more than the "
                "budget of 64.0 MiB; raise it with --max-memory (e.g. to 1G)\n");
}

TEST(BuildCommand, ChecksWhatItWrites) {
  TempDir dir;
  const std::string light = dir.write("light.json", test::spot_json());
  ASSERT_TRUE(write_depth_image(dir.file("depth.exr"), occluded_depth()).ok());
  auto r = test::run_lightvol("build '" + dir.file("depth.exr") + "' --light '" + light +
                              "' --out '" + dir.file("v.ply") + "' --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("\"checking\""), std::string::npos) << r.out;
  r = test::run_lightvol("check '" + dir.file("v.ply") + "' --light '" + light + "' -q");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  r = test::run_lightvol("build '" + dir.file("depth.exr") + "' --light '" + light + "' --out '" +
                         dir.file("w.ply") + "' --no-check --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.find("\"checking\""), std::string::npos) << r.out;
}

}  // namespace
}  // namespace lightvol
