// Omni depth input: six files, a {face} path and a W × 6W strip give the same faces and the same
// volume; missing, non-square and mismatched faces are errors naming the file and the face.
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/depth/cube_faces.h>
#include <lightvol/volume/omni_volume.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

using test::make_depth;
using test::TempDir;

// Face f holds depths that identify it and each texel.
CubeFaces distinct_cube(int w) {
  CubeFaces cube;
  for (int f = 0; f < kOmniFaces; ++f) {
    cube.faces[f] = make_depth(w, w, [f](int c, int r) {
      return static_cast<float>(1.0 + 0.5 * f + 0.01 * c + 0.001 * r);
    });
    cube.sources[f] = "memory";
  }
  return cube;
}

void write_faces(const CubeFaces& cube, const std::string& pattern) {
  for (int f = 0; f < kOmniFaces; ++f)
    ASSERT_TRUE(write_depth_image(expand_face_pattern(pattern, f), cube.faces[f]).ok());
}

std::string message_of(const Result<CubeFaces>& r) { return r ? "(no error)" : r.error().message; }

TEST(CubeFaces, FacePatternExpandsEveryPlaceholder) {
  EXPECT_EQ(expand_face_pattern("a/{face}/room_{face}.exr", 3), "a/ny/room_ny.exr");
  EXPECT_EQ(expand_face_pattern("room.exr", 0), "room.exr");
  const char* tags[] = {"px", "nx", "py", "ny", "pz", "nz"};
  for (int f = 0; f < kOmniFaces; ++f) EXPECT_EQ(expand_face_pattern("{face}", f), tags[f]);
  EXPECT_EQ(omni_face_name(5), "-Z (nz)");
}

TEST(CubeFaces, StripSplitsTopToBottomAndStacksBack) {
  const CubeFaces cube = distinct_cube(3);
  const DepthImage strip = stack_cube_faces(cube);
  ASSERT_EQ(strip.width, 3);
  ASSERT_EQ(strip.height, 18);
  EXPECT_EQ(strip.at(2, 3 * 4 + 1), cube.faces[4].at(2, 1));  // +Z is the fifth band
  Result<CubeFaces> split = split_cube_strip(strip, "strip.exr");
  ASSERT_TRUE(split.ok()) << message_of(split);
  for (int f = 0; f < kOmniFaces; ++f) EXPECT_EQ(split->faces[f].values, cube.faces[f].values);
  EXPECT_EQ(split->sources[2], "strip.exr (strip rows 6..8)");
}

TEST(CubeFaces, TheThreeInputFormsGiveIdenticalMeshes) {
  TempDir dir;
  const int w = 8;
  const CubeFaces cube = distinct_cube(w);
  write_faces(cube, dir.file("room_{face}.exr"));
  ASSERT_TRUE(write_depth_image(dir.file("strip.exr"), stack_cube_faces(cube)).ok());

  std::vector<std::string> six;
  for (int f = 0; f < kOmniFaces; ++f)
    six.push_back(dir.file("room_" + std::string(omni_face_tag(f)) + ".exr"));
  const Result<CubeFaces> from_six = read_cube_faces(six);
  const Result<CubeFaces> from_pattern = read_cube_faces({dir.file("room_{face}.exr")});
  const Result<CubeFaces> from_strip = read_cube_faces({dir.file("strip.exr")});
  ASSERT_TRUE(from_six.ok()) << message_of(from_six);
  ASSERT_TRUE(from_pattern.ok()) << message_of(from_pattern);
  ASSERT_TRUE(from_strip.ok()) << message_of(from_strip);
  for (int f = 0; f < kOmniFaces; ++f) {
    EXPECT_EQ(from_six->faces[f].values, cube.faces[f].values) << "face " << f;
    EXPECT_EQ(from_pattern->faces[f].values, cube.faces[f].values) << "face " << f;
    EXPECT_EQ(from_strip->faces[f].values, cube.faces[f].values) << "face " << f;
  }

  const Light light = test::light_from_json(
      R"({"type": "omni", "position": [0, 1, 0], "near": 0.1, "far": 10, "depth": "linear"})");
  const Result<Mesh> a = build_omni_volume(light, *from_six, {});
  const Result<Mesh> b = build_omni_volume(light, *from_pattern, {});
  const Result<Mesh> c = build_omni_volume(light, *from_strip, {});
  ASSERT_TRUE(a.ok() && b.ok() && c.ok());
  EXPECT_EQ(a->positions, b->positions);
  EXPECT_EQ(a->indices, b->indices);
  EXPECT_EQ(a->positions, c->positions);
  EXPECT_EQ(a->indices, c->indices);
  EXPECT_EQ(a->num_triangles(), 12u * w * w - 4);
}

TEST(CubeFaces, MissingFaceIsNamed) {
  TempDir dir;
  CubeFaces cube = distinct_cube(4);
  write_faces(cube, dir.file("room_{face}.exr"));
  std::remove(dir.file("room_ny.exr").c_str());
  const Result<CubeFaces> r = read_cube_faces({dir.file("room_{face}.exr")});
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message, dir.file("room_ny.exr") + ": face -Y (ny): no such file");
}

TEST(CubeFaces, NonSquareFaceIsNamed) {
  TempDir dir;
  CubeFaces cube = distinct_cube(4);
  cube.faces[4] = make_depth(4, 3, [](int, int) { return 1.0f; });
  write_faces(cube, dir.file("room_{face}.exr"));
  const Result<CubeFaces> r = read_cube_faces({dir.file("room_{face}.exr")});
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message,
            dir.file("room_pz.exr") + ": face +Z (pz): is 4x3; omni faces must be square");
}

TEST(CubeFaces, MismatchedFaceSizeIsNamed) {
  TempDir dir;
  CubeFaces cube = distinct_cube(4);
  cube.faces[5] = make_depth(8, 8, [](int, int) { return 1.0f; });
  write_faces(cube, dir.file("room_{face}.exr"));
  std::vector<std::string> six;
  for (int f = 0; f < kOmniFaces; ++f)
    six.push_back(expand_face_pattern(dir.file("room_{face}.exr"), f));
  const Result<CubeFaces> r = read_cube_faces(six);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message,
            dir.file("room_nz.exr") + ": face -Z (nz): is 8x8, but face +X (px) (" +
                dir.file("room_px.exr") + ") is 4x4; all six faces must be the same size");
}

TEST(CubeFaces, StripOfTheWrongShapeIsRejected) {
  TempDir dir;
  ASSERT_TRUE(
      write_depth_image(dir.file("strip.exr"), make_depth(8, 40, [](int, int) { return 1.0f; }))
          .ok());
  const Result<CubeFaces> r = read_cube_faces({dir.file("strip.exr")});
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(
      r.error().message.rfind(dir.file("strip.exr") + ": is 8x40; a single omni depth image must "
                                                      "be a vertical strip W x 6W",
                              0),
      0u)
      << r.error().message;
}

TEST(CubeFaces, WrongNumberOfPathsIsRejected) {
  const Result<CubeFaces> three = read_cube_faces({"a.exr", "b.exr", "c.exr"});
  ASSERT_FALSE(three.ok());
  EXPECT_NE(three.error().message.find("an omni light takes six depth images"), std::string::npos);
  EXPECT_NE(three.error().message.find("got 3 paths"), std::string::npos);
  const Result<CubeFaces> mixed = read_cube_faces({"a_{face}.exr", "b.exr"});
  ASSERT_FALSE(mixed.ok());
  EXPECT_EQ(
      mixed.error().message.rfind("a_{face}.exr: a path with {face} stands for all six faces", 0),
      0u)
      << mixed.error().message;
}

TEST(CubeFaces, BadDepthInAFaceNamesFileFaceAndPixel) {
  TempDir dir;
  CubeFaces cube = distinct_cube(4);
  cube.faces[2].values[1 * 4 + 3] = -1.0f;
  write_faces(cube, dir.file("room_{face}.exr"));
  const Result<CubeFaces> r = read_cube_faces({dir.file("room_{face}.exr")});
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message.rfind(
                dir.file("room_py.exr") + ": face +Y (py): pixel (3, 1): depth is negative", 0),
            0u)
      << r.error().message;
}

}  // namespace
}  // namespace lightvol
