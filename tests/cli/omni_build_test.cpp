// lightvol build with an omni light: the three input forms give byte-identical volumes that pass
// check --light, static and adaptive; stats splits the counts by face and seams; a missing face is
// exit 2 naming the file and the face, with nothing written.
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <lightvol/depth/cube_faces.h>
#include <lightvol/io/mesh_reader.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

using test::make_depth;
using test::q;
using test::run_lightvol;
using test::slurp;
using test::TempDir;

// Window depths: a box room around the light with one face partly open (depth 1: nothing hit).
CubeFaces room(int w) {
  CubeFaces cube;
  for (int f = 0; f < kOmniFaces; ++f) {
    cube.faces[f] = make_depth(w, w, [f, w](int c, int r) {
      if (f == 5 && c < w / 2 && r < w / 2) return 1.0f;
      return static_cast<float>(0.90 + 0.01 * f + 0.002 * c + 0.001 * r);
    });
  }
  return cube;
}

class OmniBuildCli : public ::testing::Test {
 protected:
  void SetUp() override {
    light_ = dir_.write("omni.json",
                        R"({"type": "omni", "position": [0, 1, 0], "near": 0.1, "far": 10})");
    const CubeFaces cube = room(kW);
    for (int f = 0; f < kOmniFaces; ++f)
      ASSERT_TRUE(
          write_depth_image(expand_face_pattern(dir_.file("room_{face}.exr"), f), cube.faces[f])
              .ok());
    ASSERT_TRUE(write_depth_image(dir_.file("strip.exr"), stack_cube_faces(cube)).ok());
  }
  static constexpr int kW = 12;
  TempDir dir_;
  std::string light_;
};

TEST_F(OmniBuildCli, ThreeInputFormsGiveIdenticalVolumes) {
  std::string six;
  for (int f = 0; f < kOmniFaces; ++f)
    six += q(dir_.file("room_" + std::string(omni_face_tag(f)) + ".exr")) + " ";
  const std::string common = " --light " + q(light_) + " --quiet --out ";
  const test::CommandResult a =
      run_lightvol("build " + q(dir_.file("room_{face}.exr")) + common + q(dir_.file("a.ply")) +
                   " --report " + q(dir_.file("a.json")));
  const test::CommandResult b = run_lightvol("build " + six + common + q(dir_.file("b.ply")));
  const test::CommandResult c =
      run_lightvol("build " + q(dir_.file("strip.exr")) + common + q(dir_.file("c.ply")));
  ASSERT_EQ(a.exit_code, 0) << a.err;
  ASSERT_EQ(b.exit_code, 0) << b.err;
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const std::string bytes = slurp(dir_.file("a.ply"));
  EXPECT_FALSE(bytes.empty());
  EXPECT_EQ(bytes, slurp(dir_.file("b.ply")));
  EXPECT_EQ(bytes, slurp(dir_.file("c.ply")));
  const std::string report = slurp(dir_.file("a.json"));
  EXPECT_NE(report.find("\"triangles\": " + std::to_string(12 * kW * kW - 4)), std::string::npos)
      << report;
  EXPECT_NE(report.find("\"vertices\": " + std::to_string(6 * kW * kW)), std::string::npos)
      << report;

  const test::CommandResult check =
      run_lightvol("check " + q(dir_.file("a.ply")) + " --light " + q(light_));
  EXPECT_EQ(check.exit_code, 0) << check.out << check.err;
}

TEST_F(OmniBuildCli, AdaptiveBuildPassesCheckWithTheLight) {
  const test::CommandResult r =
      run_lightvol("build " + q(dir_.file("strip.exr")) + " --light " + q(light_) +
                   " --quiet --adaptive --max-error 0.05" + " --out " + q(dir_.file("ad.ply")) +
                   " --report " + q(dir_.file("ad.json")));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string report = slurp(dir_.file("ad.json"));
  EXPECT_NE(report.find("\"mode\": \"adaptive\""), std::string::npos) << report;
  EXPECT_NE(report.find("\"max_error_reached\""), std::string::npos) << report;
  const test::CommandResult check =
      run_lightvol("check " + q(dir_.file("ad.ply")) + " --light " + q(light_));
  EXPECT_EQ(check.exit_code, 0) << check.out << check.err;
}

// Draco at its default 16 bits, compressed GLB and DRC: the files are Draco (the DRC's "DRACO"
// magic; the GLB's primitive compressed with KHR_draco_mesh_compression, which it requires), they
// decode to closed volumes with the triangle and vertex counts of the same volume written as PLY,
// on a 16-bit quantization grid, and build verifies the decoded volume with the light, and check
// --light agrees.
TEST_F(OmniBuildCli, DracoBuildPassesCheckWithTheLight) {
  const std::string adaptive = " --light " + q(light_) + " --quiet --adaptive --max-error 0.05";
  const test::CommandResult plain = run_lightvol("build " + q(dir_.file("strip.exr")) + adaptive +
                                                 " --out " + q(dir_.file("v.ply")));
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  Result<Mesh> exact = read_mesh(dir_.file("v.ply"));
  ASSERT_TRUE(exact.ok()) << exact.error().message;
  ASSERT_TRUE(test::is_closed_and_oriented(*exact));
  for (const std::string out : {"v.drc", "v.glb"}) {
    SCOPED_TRACE(out);
    const test::CommandResult r =
        run_lightvol("build " + q(dir_.file("strip.exr")) + adaptive + " --out " +
                     q(dir_.file(out)) + (out == "v.glb" ? " --draco" : ""));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string bytes = slurp(dir_.file(out));
    if (out == "v.drc") {
      EXPECT_EQ(bytes.substr(0, 5), "DRACO");
    } else {
      ASSERT_GT(bytes.size(), 20u);
      EXPECT_EQ(bytes.substr(0, 4), "glTF");
      std::uint32_t json_length = 0;
      std::memcpy(&json_length, bytes.data() + 12, 4);
      const auto json = nlohmann::json::parse(bytes.substr(20, json_length));
      EXPECT_EQ(json["extensionsRequired"], nlohmann::json::array({"KHR_draco_mesh_compression"}));
      EXPECT_TRUE(
          json["meshes"][0]["primitives"][0]["extensions"].contains("KHR_draco_mesh_compression"));
    }
    double step = 0;
    Result<Mesh> decoded = read_mesh(dir_.file(out), &step);
    ASSERT_TRUE(decoded.ok()) << decoded.error().message;
    EXPECT_TRUE(test::is_closed_and_oriented(*decoded));
    EXPECT_EQ(decoded->num_triangles(), exact->num_triangles());
    EXPECT_EQ(decoded->num_vertices(), exact->num_vertices());
    EXPECT_GT(step, 0);  // quantized: decoded by Draco
    const test::CommandResult check =
        run_lightvol("check " + q(dir_.file(out)) + " --light " + q(light_));
    EXPECT_EQ(check.exit_code, 0) << check.out << check.err;
  }
}

TEST_F(OmniBuildCli, StatsReportsFacesAndSeams) {
  const test::CommandResult r =
      run_lightvol("stats " + q(dir_.file("room_{face}.exr")) + " --light " + q(light_) +
                   " --max-error 0.01,0.1 --csv");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::istringstream lines(r.out);
  std::string header, static_row, fine, coarse;
  std::getline(lines, header);
  std::getline(lines, static_row);
  std::getline(lines, fine);
  std::getline(lines, coarse);
  EXPECT_EQ(header,
            "mode,max_error,triangles,vertices,max_error_reached,px,nx,py,ny,pz,nz,seams,corners,"
            "tessellation,min_angle_degrees,min_area_texels");
  // Static: 12W² − 4 triangles, 2(W − 1)² per face, 24(W − 1) in the seams, 8 corners.
  const int w = kW;
  std::string expected =
      "static,," + std::to_string(12 * w * w - 4) + "," + std::to_string(6 * w * w) + ",0";
  for (int f = 0; f < kOmniFaces; ++f) expected += "," + std::to_string(2 * (w - 1) * (w - 1));
  EXPECT_EQ(static_row, expected + "," + std::to_string(24 * (w - 1)) + ",8,,,");
  EXPECT_EQ(fine.rfind("adaptive,0.01,", 0), 0u) << fine;
  EXPECT_EQ(coarse.rfind("adaptive,0.1,", 0), 0u) << coarse;
  EXPECT_NE(fine.find(",collapse,"), std::string::npos) << fine;
}

TEST_F(OmniBuildCli, MissingFaceIsExit2NamingFileAndFace) {
  std::remove(dir_.file("room_pz.exr").c_str());
  const test::CommandResult r =
      run_lightvol("build " + q(dir_.file("room_{face}.exr")) + " --light " + q(light_) +
                   " --out " + q(dir_.file("v.ply")));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "lightvol: " + dir_.file("room_pz.exr") + ": face +Z (pz): no such file\n");
  std::ifstream written(dir_.file("v.ply"));
  EXPECT_FALSE(written.good()) << "a failed build wrote its output";
}

TEST_F(OmniBuildCli, WrongNumberOfFacesIsExit2) {
  const test::CommandResult r =
      run_lightvol("build " + q(dir_.file("room_px.exr")) + " " + q(dir_.file("room_nx.exr")) +
                   " --light " + q(light_) + " --out " + q(dir_.file("v.ply")));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("an omni light takes six depth images"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace lightvol
