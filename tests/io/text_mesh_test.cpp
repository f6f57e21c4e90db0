// The text mesh formats (ASCII STL, OBJ, OFF, ASCII PLY) read a coordinate as a finite float or
// refuse it naming the line: "nan", "inf", "abc" and 1e39 are never read as numbers (OpenMesh's
// ASCII STL reader left them as whatever the memory held). ASCII STL is lightvol's own reader:
// its structure is checked line by line.
#include <algorithm>
#include <iterator>
#include <string>

#include <gtest/gtest.h>

#include <lightvol/core/mesh.h>
#include <lightvol/io/mesh_reader.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

using test::TempDir;

// A tetrahedron (vertices 0 0 0, 1 0 0, 0 1 0, 0 0 1, faces outward) in each text format, with
// '@' where vertex 2's y coordinate goes (STL: each time), and the name of its first line in
// messages.
struct Format {
  std::string name, text, line;
};

std::string stl_facet(const std::string& a, const std::string& b, const std::string& c) {
  return "  facet normal 0 0 0\n    outer loop\n      vertex " + a + "\n      vertex " + b +
         "\n      vertex " + c + "\n    endloop\n  endfacet\n";
}

const Format kFormats[] = {
    {"t.stl",
     "solid t\n" + stl_facet("0 0 0", "0 @ 0", "1 0 0") + stl_facet("0 0 0", "1 0 0", "0 0 1") +
         stl_facet("0 0 0", "0 0 1", "0 @ 0") + stl_facet("1 0 0", "0 @ 0", "0 0 1") +
         "endsolid t\n",
     "STL line 5"},
    {"t.obj", "v 0 0 0\nv 1 0 0\nv 0 @ 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
     "OBJ line 3"},
    {"t.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 @ 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n",
     "OFF line 5"},
    {"t.ply",
     "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
     "property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n"
     "0 0 0\n1 0 0\n0 @ 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n",
     "PLY body line 3"},
};

std::string with(const std::string& text, const std::string& word) {
  std::string out = text;
  for (std::size_t at = out.find('@'); at != std::string::npos; at = out.find('@', at))
    out.replace(at, 1, word);
  return out;
}

TEST(TextMesh, CoordinatesThatAreNoFiniteFloatAreRefusedNamingTheLine) {
  TempDir dir;
  for (const Format& f : kFormats) {
    for (const std::string word : {"1", "+1", "1.0e0", "0.5", "3.4e38"}) {
      const Result<Mesh> mesh = read_mesh(dir.write(f.name, with(f.text, word)));
      ASSERT_TRUE(mesh.ok()) << f.name << " with " << word << ": " << mesh.error().message;
      EXPECT_EQ(mesh->num_triangles(), 4u) << f.name;
      EXPECT_EQ(mesh->num_vertices(), 4u) << f.name;
    }
    for (const std::string word : {"nan", "NaN", "-nan", "inf", "-infinity", "abc", "1e39", "-1e39",
                                   "3.5e38", "1e400", "0x10", "1,5", "--1"}) {
      const std::string path = dir.write(f.name, with(f.text, word));
      const Result<Mesh> mesh = read_mesh(path);
      ASSERT_FALSE(mesh.ok()) << f.name << " with " << word;
      EXPECT_EQ(mesh.error().message,
                path + ": " + f.line + ": '" + word +
                    "' is not a coordinate (a finite number within a float's range)");
    }
  }
}

TEST(TextMesh, HomogeneousOffVerticesAreFiniteFloatsToo) {
  TempDir dir;
  const std::string faces = "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
  const auto read = [&](const std::string& vertex) {
    return read_mesh(
        dir.write("h.off", "4OFF\n4 4 0\n0 0 0 1\n1 0 0 1\n" + vertex + "\n0 0 1 1\n" + faces));
  };
  ASSERT_TRUE(read("0 2 0 2").ok());
  const std::string path = dir.file("h.off");
  EXPECT_EQ(
      read("0 1 0 nan").error().message,
      path + ": OFF line 5: 'nan' is not a coordinate (a finite number within a float's range)");
  EXPECT_EQ(read("0 1e300 0 1e-300").error().message,
            path +
                ": OFF line 5: vertex 2 divided by its homogeneous coordinate is beyond a float's "
                "range");
}

TEST(TextMesh, AsciiStlSolidsInAnyCaseAndDegenerateFacetsDropped) {
  TempDir dir;
  const std::string& tetra = kFormats[0].text;
  // Two solids, upper-case keywords, a facet without a normal, a degenerate facet.
  const std::string text = with(tetra, "1") + "SOLID second\n FACET\n OUTER LOOP\n VERTEX 5 5 5\n" +
                           " VERTEX 5 5 5\n VERTEX 6 5 5\n ENDLOOP\n ENDFACET\nENDSOLID\n";
  const Result<Mesh> mesh = read_mesh(dir.write("two.stl", text));
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  EXPECT_EQ(mesh->num_triangles(), 4u);
  EXPECT_NEAR(signed_volume(*mesh), 1.0 / 6, 1e-7);
}

TEST(TextMesh, AsciiStlOutOfOrderOrCutIsRefusedNamingTheLine) {
  TempDir dir;
  const std::string head = "solid t\n  facet normal 0 0 1\n    outer loop\n";
  const std::string three = "vertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n";
  const struct {
    std::string text, message;
  } cases[] = {
      {"solid t\nvertex 0 0 0\n", "STL line 2: expected 'facet' or 'endsolid', got 'vertex'"},
      {"solid t\nhello\n", "STL line 2: expected 'facet' or 'endsolid', got 'hello'"},
      {"solid t\nfacet normal 0 0 1\nvertex 0 0 0\n",
       "STL line 3: expected 'outer loop', got 'vertex'"},
      {"solid t\nfacet\nouter\n", "STL line 3: expected 'outer loop'"},
      {head + "vertex 0 0 0\nvertex 1 0 0\nendloop\n", "STL line 6: facet 0 has 2 vertices, not 3"},
      {head + three + "vertex 1 1 0\n", "STL line 7: expected 'endloop', got 'vertex'"},
      {head + "vertex 0 0\n", "STL line 4: expected 'vertex x y z'"},
      {head + "vertex 0 0 0 1\n", "STL line 4: expected 'vertex x y z'"},
      {head + three + "endloop\nendloop\n", "STL line 8: expected 'endfacet', got 'endloop'"},
      {head + three + "endloop\nendfacet\nsolid u\n",
       "STL line 9: expected 'facet' or 'endsolid', got 'solid'"},
      {head + three + "endloop\nendfacet\nendsolid t\nendsolid t\n",
       "STL line 10: expected 'solid', got 'endsolid'"},
      {head + three, "STL file ends after line 6, inside a facet (truncated?)"},
      {head + three + "endloop\nendfacet\n",
       "STL file ends after line 8, inside a solid (no 'endsolid'; truncated?)"},
      {head + three + "endloop\nendfacet\n" + std::string(600, ' ') + std::string("\0\n", 2),
       "not an ASCII STL file (binary data in line 9)"},
  };
  for (const auto& c : cases) {
    const std::string path = dir.write("bad.stl", c.text);
    const Result<Mesh> mesh = read_mesh(path);
    ASSERT_FALSE(mesh.ok()) << c.message;
    EXPECT_EQ(mesh.error().message, path + ": " + c.message);
  }
}

// What follows the last element, format by format (docs/formats.md): blank lines (and comments,
// where the format has them) are fine; anything else is refused naming the line. OBJ is a list of
// statements with no last element: it is read to its end, whatever statements it holds.
TEST(TextMesh, TextAfterTheLastElementIsRefusedWhereTheFormatHasALastElement) {
  TempDir dir;
  struct Case {
    std::string name, after, message;  // message: "" when accepted
  };
  const Case cases[] = {
      {"t.stl", "\n \n", ""},
      {"t.stl", "solid u\nendsolid u\n", ""},  // several solids in one file
      {"t.stl", "3 0 1 2\n", "STL line 31: expected 'solid', got '3'"},
      {"t.off", "\n# the end\n  \n", ""},
      {"t.off", "3 1 3 2\n",
       "OFF line 11: text after the last face: '3'; an OFF file ends with its faces (comments and "
       "blank lines aside)"},
      {"t.off", "# a comment\n4 4 0\n",
       "OFF line 12: text after the last face: '4'; an OFF file ends with its faces (comments and "
       "blank lines aside)"},
      {"t.ply", " \n\r\n", ""},
      {"t.ply", "end\n",
       "PLY body line 9: text after the last element ('face'): 'end'; an ASCII PLY file ends "
       "with its last element (blank lines aside)"},
      {"t.obj", "vn 0 0 1\ng rest\n", ""},
  };
  for (const Case& c : cases) {
    const Format& format = *std::find_if(std::begin(kFormats), std::end(kFormats),
                                         [&](const Format& f) { return f.name == c.name; });
    const std::string path = dir.write(c.name, with(format.text, "1") + c.after);
    const Result<Mesh> mesh = read_mesh(path);
    if (c.message.empty()) {
      ASSERT_TRUE(mesh.ok()) << c.name << ": " << mesh.error().message;
      EXPECT_EQ(mesh->num_triangles(), 4u) << c.name;
    } else {
      ASSERT_FALSE(mesh.ok()) << c.name << " " << c.after;
      EXPECT_EQ(mesh.error().message, path + ": " + c.message);
    }
  }
}

}  // namespace
}  // namespace lightvol
