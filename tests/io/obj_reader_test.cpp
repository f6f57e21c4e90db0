// The OBJ reader: positions and faces in every face-vertex form, relative and forward indices,
// nothing else opened; malformed lines refused with the file and line named.
#include <string>

#include <gtest/gtest.h>

#include <lightvol/io/mesh_reader.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

using test::TempDir;

TEST(ReadObj, FaceVertexFormsRelativeAndForwardIndices) {
  TempDir dir;
  // A quad (v//n and negative indices) and a triangle naming a vertex defined after it (v/t/n).
  const std::string path = dir.write(
      "q.obj",
      "# a comment\nmtllib scene.mtl\no quad\nv 0 0 0\nv +1 0 0 1\nvt 0 0\nvn 0 0 1\nv 1 1 0 0.5 "
      "0.5 0.5\n"
      "v 0 1 0 # trailing comment\nusemtl stone\ns off\nf -4//1 -3//1 -2//1 -1//1\ng tri\n"
      "f 1/1/1 3/1 5\nl 1 2\nv 0.5 0.25 -2.5\n");
  const Result<Mesh> mesh = read_mesh(path);
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  ASSERT_EQ(mesh->num_vertices(), 5u);
  ASSERT_EQ(mesh->num_triangles(), 3u);
  EXPECT_EQ(mesh->vertex(1), (std::array<float, 3>{1, 0, 0}));
  EXPECT_EQ(mesh->vertex(4), (std::array<float, 3>{0.5f, 0.25f, -2.5f}));
  EXPECT_EQ(mesh->triangle(0), (std::array<std::uint32_t, 3>{0, 1, 2}));
  EXPECT_EQ(mesh->triangle(1), (std::array<std::uint32_t, 3>{0, 2, 3}));
  EXPECT_EQ(mesh->triangle(2), (std::array<std::uint32_t, 3>{0, 2, 4}));
}

TEST(ReadObj, MaterialLibrariesAreNeverOpened) {
  // OpenMesh's reader followed 'mtllib' relative to the OBJ's folder and read /dev/zero forever.
  TempDir dir;
  std::string up;
  for (int i = 0; i < 32; ++i) up += "../";
  const std::string path =
      dir.write("zero.obj", "mtllib " + up + "dev/zero\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const Result<Mesh> mesh = read_mesh(path);
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  EXPECT_EQ(mesh->num_triangles(), 1u);
}

TEST(ReadObj, MalformedLinesAreRefusedNamingTheLine) {
  TempDir dir;
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  const struct {
    std::string text, message;
  } cases[] = {
      {tri + "f /1 2 3\n", "OBJ line 4: face vertex '/1' is not v, v/t, v//n or v/t/n"},
      {tri + "f 1//x 2 3\n", "OBJ line 4: face vertex '1//x' is not v, v/t, v//n or v/t/n"},
      {tri + "f 1/2/3/4 2 3\n", "OBJ line 4: face vertex '1/2/3/4' is not v, v/t, v//n or v/t/n"},
      {tri + "f 1 2\n", "OBJ line 4: face 0 has 2 vertices"},
      {tri + "f 0 1 2\n", "OBJ line 4: face 0 names vertex 0, but there are 3 before it"},
      {tri + "f -4 1 2\n", "OBJ line 4: face 0 names vertex -4, but there are 3 before it"},
      {tri + "f 1 2 3\nf 1 2 9\n", "OBJ line 5: face 1 names vertex 9, but there are 3"},
      {"v 0 0\n", "OBJ line 1: expected a vertex 'v x y z', got 'v 0 0'"},
      {"v 0 zero 0\n",
       "OBJ line 1: 'zero' is not a coordinate (a finite number within a float's range)"},
      {tri + "f 1 2 3\nv 0 0 1\n" + std::string("f 1\0 2 3\n", 9),
       "not an OBJ file (binary data in a text format)"},
      {"v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n",
       "OBJ line 2: 'nan' is not a coordinate (a finite number within a float's range)"},
  };
  for (const auto& c : cases) {
    const std::string path = dir.write("bad.obj", c.text);
    const Result<Mesh> mesh = read_mesh(path);
    ASSERT_FALSE(mesh.ok()) << c.message;
    EXPECT_EQ(mesh.error().message, path + ": " + c.message);
  }
}

}  // namespace
}  // namespace lightvol
