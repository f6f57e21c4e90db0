// The PLY reader: every encoding and value type the format allows, elements in any order, other
// elements and properties skipped; and every malformed header, line or element refused with a
// message naming the file and where.
#include <bit>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/io/mesh_reader.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

using test::TempDir;

// Appends `v` as `T` in the byte order of `big`.
template <class T>
void put(std::string* out, double v, bool big) {
  const T value = static_cast<T>(v);
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  static_assert(std::endian::native == std::endian::little);
  if (big) std::reverse(bytes, bytes + sizeof(T));
  out->append(bytes, sizeof(T));
}

// A unit square as two faces of a quad and a triangle (0 1 2 3, then 0 2 4), with a vertex
// element carrying extra properties and an extra element in front of everything.
const float kSquare[5][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5f, 0.25f, -2.5f}};

std::string binary_square(bool big) {
  std::string ply = std::string("ply\nformat ") +
                    (big ? "binary_big_endian" : "binary_little_endian") +
                    " 1.0\ncomment extra element first\nelement material 2\nproperty uchar red\n"
                    "property list ushort float weights\n"
                    "element vertex 5\nproperty double x\nproperty short flag\nproperty double y\n"
                    "property float z\nproperty list uchar int uvs\n"
                    "element face 2\nproperty list uint uint vertex_indices\nproperty int8 group\n"
                    "end_header\n";
  for (int m = 0; m < 2; ++m) {
    put<std::uint8_t>(&ply, 200, big);
    put<std::uint16_t>(&ply, 2, big);
    put<float>(&ply, 0.5, big);
    put<float>(&ply, 1.5, big);
  }
  for (const auto& v : kSquare) {
    put<double>(&ply, v[0], big);
    put<std::int16_t>(&ply, -7, big);
    put<double>(&ply, v[1], big);
    put<float>(&ply, v[2], big);
    put<std::uint8_t>(&ply, 1, big);
    put<std::int32_t>(&ply, 99, big);
  }
  put<std::uint32_t>(&ply, 4, big);
  for (const int i : {0, 1, 2, 3}) put<std::uint32_t>(&ply, i, big);
  put<std::int8_t>(&ply, -1, big);
  put<std::uint32_t>(&ply, 3, big);
  for (const int i : {0, 2, 4}) put<std::uint32_t>(&ply, i, big);
  put<std::int8_t>(&ply, 5, big);
  return ply;
}

void expect_square(const Result<Mesh>& mesh) {
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  ASSERT_EQ(mesh->num_vertices(), 5u);
  ASSERT_EQ(mesh->num_triangles(), 3u);
  for (std::size_t v = 0; v < 5; ++v)
    EXPECT_EQ(mesh->vertex(v), (std::array<float, 3>{kSquare[v][0], kSquare[v][1], kSquare[v][2]}))
        << v;
  EXPECT_EQ(mesh->triangle(0), (std::array<std::uint32_t, 3>{0, 1, 2}));
  EXPECT_EQ(mesh->triangle(1), (std::array<std::uint32_t, 3>{0, 2, 3}));
  EXPECT_EQ(mesh->triangle(2), (std::array<std::uint32_t, 3>{0, 2, 4}));
}

TEST(ReadPly, BinaryBothByteOrdersWithOtherElementsAndProperties) {
  TempDir dir;
  expect_square(read_mesh(dir.write("le.ply", binary_square(false))));
  expect_square(read_mesh(dir.write("be.ply", binary_square(true))));
}

TEST(ReadPly, AsciiFacesBeforeVerticesBlankLinesAndCrLf) {
  TempDir dir;
  expect_square(read_mesh(dir.write(
      "a.ply",
      "ply\r\nformat ascii 1.0\r\nelement face 2\r\nproperty list uchar int vertex_index\r\n"
      "element vertex 5\r\nproperty float x\r\nproperty float y\r\nproperty float z\r\n"
      "property list int float extra\r\nend_header\r\n"
      "4 0 1 2 3\r\n\r\n3 0 2 4\r\n0 0 0 0\r\n1 0 0 2 7 8\r\n  1\t1 0 0\r\n0 1 0 0\r\n"
      "0.5 0.25 -2.5 1 -1e3\r\n")));
}

// Before: old Blender's header line without the 'comment' keyword (assimp's Wuson.ply) was refused
// as an unknown keyword. Free text before the first element is read as a comment; after it, an
// unknown keyword is still an error (a misspelt property would otherwise vanish).
TEST(ReadPly, FreeTextBeforeTheFirstElementIsAComment) {
  TempDir dir;
  expect_square(
      read_mesh(dir.write("wuson.ply",
                          "ply\nformat ascii 1.0\n"
                          "Created by Blender3D 247 - www.blender.org, source file: 'wuson.blend'\n"
                          "element vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
                          "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
                          "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.25 -2.5\n4 0 1 2 3\n3 0 2 4\n")));
  const std::string late = dir.write(
      "late.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproprety float x\nend_header\n0\n");
  const Result<Mesh> mesh = read_mesh(late);
  ASSERT_FALSE(mesh.ok());
  EXPECT_NE(mesh.error().message.find("PLY header line 4: unknown keyword 'proprety'"),
            std::string::npos)
      << mesh.error().message;
}

TEST(ReadPly, AsciiAsShortAsTheFormatAllowsWithoutAFinalNewline) {
  // Every value one character and one separator, the last newline missing: exactly at the bound
  // the header's counts are checked against.
  TempDir dir;
  const Result<Mesh> tet =
      read_mesh(dir.write("tet.ply",
                          "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty "
                          "float y\nproperty float z\n"
                          "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
                          "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3"));
  ASSERT_TRUE(tet.ok()) << tet.error().message;
  EXPECT_EQ(tet->num_triangles(), 4u);
  EXPECT_DOUBLE_EQ(signed_volume(*tet), 1.0 / 6.0);
}

TEST(ReadPly, MalformedFilesAreRefusedNamingWhere) {
  TempDir dir;
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\n";
  const std::string body = "end_header\n0 0 0\n1 0 0\n0 1 0\n";
  // Blank lines after the last element are ignored; they keep the body as long as the header's
  // counts need (two characters a value), so that the body's own checks are reached.
  const std::string pad = "\n\n\n\n";
  const struct {
    std::string text, message;
  } cases[] = {
      {"ply\nformat ascii 1.0\nelement\nend_header\n",  // fuzz finding: OpenMesh looped forever
       "PLY header line 3: expected 'element NAME COUNT' with a whole-number COUNT"},
      {"ply\nformat ascii 1.0\nelement vertex -3\nend_header\n",
       "PLY header line 3: expected 'element NAME COUNT' with a whole-number COUNT"},
      {"ply\nformat ascii 1.0\nelement vertex 99999999999999999999999\nproperty float x\nproperty "
       "float y\n"
       "property float z\nend_header\n",
       "PLY header: 18446744073709551615 vertex elements cannot fit in"},
      {"ply\nformat ascii 1.0\nproperty float x\nend_header\n",
       "PLY header line 3: a property before any element"},
      {"ply\nformat ascii 1.0\nformat ascii 1.0\nend_header\n",
       "PLY header line 3: a second 'format' line"},
      {"ply\nelement vertex 1\nproperty float x\nend_header\n0\n",
       "PLY header has no 'format' line"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nelement vertex 1\nend_header\n",
       "PLY header line 4: a second element 'vertex'"},
      {"ply\nformat ascii 1.0\nelement v 1\nproperty list float int vertex_indices\nend_header\n",
       "PLY header line 4: a list's count must be of an integer type, not 'float'"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header "
       "extra\n",
       "PLY header line 6: expected 'end_header' alone"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 "
       "0\n",
       "PLY header: element 'vertex' has no property 'z'"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty "
       "float z\n"
       "element face 1\nproperty list uchar int corners\nend_header\n0 0 0\n3 0 0 0\n",
       "PLY header: element 'face' has no list property 'vertex_indices'"},
      {"ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int "
       "vertex_indices\nend_header\n3 0 1 2\n",
       "PLY header declares no 'element vertex'"},
      {head + body + "3 0 1 3\n" + pad, "PLY body line 4: face 0 names vertex 3, but there are 3"},
      {head + body + "3 0 1 -1\n" + pad,
       "PLY body line 4: face 0 names vertex -1, but there are 3"},
      {head + body + "3 0 1 1.5\n" + pad,
       "PLY body line 4: face 0 names vertex 1.5, but there are 3"},
      {head + body + "2 0 1\n" + pad, "PLY body line 4: face 0 has 2 vertices"},
      {head + body + "3 0 1 2 7\n" + pad,
       "PLY body line 4: 5 values, more than the properties of element 'face' take (4)"},
      {head + body + "3 0 1\n" + pad, "PLY body line 4: a list of 3 items on a line of 3 values"},
      {head + body + "3 0 one 2\n" + pad, "PLY body line 4: 'one' is not a number"},
      {head + "end_header\n0 0 0\n1 0\n0 1 0\n3 0 1 2\n" + pad,
       "PLY body line 2: 2 values, too few for the properties of element 'vertex'"},
      {head + body + pad + pad, "PLY file ends after 0 of 1 face elements (truncated?)"},
      {head + body, "PLY header: 1 face elements cannot fit in"},
  };
  for (const auto& c : cases) {
    const std::string path = dir.write("bad.ply", c.text);
    const Result<Mesh> mesh = read_mesh(path);
    ASSERT_FALSE(mesh.ok()) << c.message;
    EXPECT_EQ(mesh.error().message.rfind(path + ": " + c.message, 0), 0u) << mesh.error().message;
  }
}

TEST(ReadPly, BinaryCutShortOrListingBeyondItsEnd) {
  TempDir dir;
  const std::string whole = binary_square(false);
  // Cut inside the last face's list: the header's counts still fit, the body does not.
  const std::string cut = dir.write("cut.ply", whole.substr(0, whole.size() - 3));
  const Result<Mesh> short_mesh = read_mesh(cut);
  ASSERT_FALSE(short_mesh.ok());
  EXPECT_EQ(
      short_mesh.error().message,
      cut + ": PLY body: face element 1: a list of 3 items, more than the rest of the file holds");
  const std::string skipped = dir.write("skip.ply", whole.substr(0, whole.size() - 15));
  const Result<Mesh> truncated = read_mesh(skipped);
  ASSERT_FALSE(truncated.ok());
  EXPECT_EQ(truncated.error().message.rfind(skipped + ": PLY", 0), 0u) << truncated.error().message;
}

// The layout lightvol writes (float x y z; a uchar-counted int list), which the reader takes a
// buffer of records at a time: triangles, and between them a quad, then each way that layout
// can go wrong, reported as element by element.
std::string plain_ply(bool big, const std::vector<std::vector<double>>& faces,
                      std::size_t vertices = 4) {
  std::string ply =
      std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
      " 1.0\nelement vertex " + std::to_string(vertices) +
      "\nproperty float x\nproperty float y\nproperty float z\n"
      "element face " +
      std::to_string(faces.size()) + "\nproperty list uchar int vertex_indices\nend_header\n";
  for (std::size_t v = 0; v < vertices; ++v)
    for (int k = 0; k < 3; ++k)
      put<float>(&ply, kSquare[v % 5][k] + 2.0 * static_cast<double>(v / 5), big);
  for (const auto& f : faces) {
    put<std::uint8_t>(&ply, static_cast<double>(f.size()), big);
    for (const double i : f) put<std::int32_t>(&ply, i, big);
  }
  return ply;
}

TEST(ReadPly, PlainLayoutInBulkWithPolygonsAndEachBadFace) {
  TempDir dir;
  for (const bool big : {false, true}) {
    SCOPED_TRACE(big);
    const std::string path =
        dir.write("plain.ply", plain_ply(big, {{0, 1, 2}, {0, 1, 2, 3}, {3, 2, 1}}));
    const Result<Mesh> mesh = read_mesh(path);
    ASSERT_TRUE(mesh.ok()) << mesh.error().message;
    ASSERT_EQ(mesh->num_triangles(), 4u);
    EXPECT_EQ(mesh->triangle(0), (std::array<std::uint32_t, 3>{0, 1, 2}));
    EXPECT_EQ(mesh->triangle(1), (std::array<std::uint32_t, 3>{0, 1, 2}));
    EXPECT_EQ(mesh->triangle(2), (std::array<std::uint32_t, 3>{0, 2, 3}));
    EXPECT_EQ(mesh->triangle(3), (std::array<std::uint32_t, 3>{3, 2, 1}));
    EXPECT_EQ(mesh->vertex(3), (std::array<float, 3>{0, 1, 0}));

    const auto expect_error = [&](const std::string& text, const std::string& message) {
      const std::string bad = dir.write("bad.ply", text);
      const Result<Mesh> m = read_mesh(bad);
      ASSERT_FALSE(m.ok()) << message;
      EXPECT_EQ(m.error().message, bad + ": " + message);
    };
    expect_error(plain_ply(big, {{0, 1, 2}, {0, 1, 4}}),
                 "PLY body: face 1 names vertex 4, but there are 4");
    expect_error(plain_ply(big, {{0, 1, 2}, {1, 2, 3}, {0, -1, 2}}),
                 "PLY body: face 2 names vertex -1, but there are 4");
    expect_error(plain_ply(big, {{0, 1, 2}, {0, 1}, {0, 1, 2, 3}}),
                 "PLY body: face 1 has 2 vertices");
    // Vertices of another count than the faces use.
    const std::string whole = plain_ply(big, {{0, 1, 2}, {1, 2, 3}, {2, 3, 0}, {3, 0, 1}}, 5);
    const Result<Mesh> ok = read_mesh(dir.write("five.ply", whole));
    ASSERT_TRUE(ok.ok()) << ok.error().message;
    EXPECT_EQ(ok->num_vertices(), 5u);
  }
  // Many records: more than one buffer of them (1 MiB), a quad in the middle.
  std::vector<std::vector<double>> many(200000, {0, 1, 2});
  many[123456] = {0, 1, 2, 3};
  const Result<Mesh> big_mesh = read_mesh(dir.write("many.ply", plain_ply(false, many, 100000)));
  ASSERT_TRUE(big_mesh.ok()) << big_mesh.error().message;
  EXPECT_EQ(big_mesh->num_triangles(), 200001u);
  EXPECT_EQ(big_mesh->triangle(123457), (std::array<std::uint32_t, 3>{0, 2, 3}));
  EXPECT_EQ(big_mesh->vertex(99999)[0], kSquare[99999 % 5][0] + 2.0f * (99999 / 5));
}

// Elements of 65,536 records or more are read in parallel blocks (of 256 KiB): the same mesh and
// the same messages as record by record, whichever block the first bad face falls in.
std::string big_ply(bool big, std::size_t vertices, const std::vector<std::vector<double>>& faces,
                    bool extra) {
  std::string ply = std::string("ply\nformat ") +
                    (big ? "binary_big_endian" : "binary_little_endian") + " 1.0\nelement vertex " +
                    std::to_string(vertices) +
                    (extra ? "\nproperty uchar red\nproperty double x\nproperty float y\nproperty "
                             "float z\nproperty short s\n"
                           : "\nproperty float x\nproperty float y\nproperty float z\n") +
                    "element face " + std::to_string(faces.size()) +
                    "\nproperty list uchar uint vertex_indices\nend_header\n";
  for (std::size_t v = 0; v < vertices; ++v) {
    const double x = static_cast<double>(v) * 0.5, y = -static_cast<double>(v % 977), z = 0.25;
    if (extra) {
      put<std::uint8_t>(&ply, 7, big);
      put<double>(&ply, x, big);
    } else {
      put<float>(&ply, x, big);
    }
    put<float>(&ply, y, big);
    put<float>(&ply, z, big);
    if (extra) put<std::int16_t>(&ply, -3, big);
  }
  for (const auto& f : faces) {
    put<std::uint8_t>(&ply, static_cast<double>(f.size()), big);
    for (const double i : f) put<std::uint32_t>(&ply, i, big);
  }
  return ply;
}

TEST(ReadPly, BigElementsInParallelBlocks) {
  TempDir dir;
  constexpr std::size_t kVertices = 100000, kFaces = 250000;  // 19 blocks of faces
  std::vector<std::vector<double>> faces(kFaces);
  for (std::size_t t = 0; t < kFaces; ++t)
    faces[t] = {static_cast<double>(t % kVertices), static_cast<double>((t * 7 + 1) % kVertices),
                static_cast<double>((t * 13 + 5) % kVertices)};
  for (const bool big : {false, true}) {
    for (const bool extra : {false, true}) {
      SCOPED_TRACE(std::to_string(big) + " " + std::to_string(extra));
      const Result<Mesh> mesh =
          read_mesh(dir.write("big.ply", big_ply(big, kVertices, faces, extra)));
      ASSERT_TRUE(mesh.ok()) << mesh.error().message;
      ASSERT_EQ(mesh->num_vertices(), kVertices);
      ASSERT_EQ(mesh->num_triangles(), kFaces);
      bool same = true;
      for (std::size_t v = 0; v < kVertices; ++v)
        same &= mesh->vertex(v) == std::array<float, 3>{static_cast<float>(v) * 0.5f,
                                                        -static_cast<float>(v % 977), 0.25f};
      for (std::size_t t = 0; t < kFaces; ++t)
        for (int k = 0; k < 3; ++k) same &= mesh->indices[3 * t + k] == faces[t][k];
      EXPECT_TRUE(same);
    }
  }
  // A quad in a late block: fan-triangulated, and the faces after it read record by record.
  std::vector<std::vector<double>> with_quad = faces;
  with_quad[200001] = {1, 2, 3, 4};
  const Result<Mesh> quad =
      read_mesh(dir.write("quad.ply", big_ply(false, kVertices, with_quad, false)));
  ASSERT_TRUE(quad.ok()) << quad.error().message;
  ASSERT_EQ(quad->num_triangles(), kFaces + 1);
  EXPECT_EQ(quad->triangle(200000)[0], faces[200000][0]);
  EXPECT_EQ(quad->triangle(200001), (std::array<std::uint32_t, 3>{1, 2, 3}));
  EXPECT_EQ(quad->triangle(200002), (std::array<std::uint32_t, 3>{1, 3, 4}));
  EXPECT_EQ(quad->triangle(kFaces)[2], faces[kFaces - 1][2]);

  // The first bad face is reported, wherever the blocks that hold bad faces run.
  const auto expect_error = [&](std::vector<std::vector<double>> bad_faces,
                                const std::string& message) {
    const std::string path = dir.write("bad.ply", big_ply(false, kVertices, bad_faces, false));
    const Result<Mesh> m = read_mesh(path);
    ASSERT_FALSE(m.ok()) << message;
    EXPECT_EQ(m.error().message, path + ": " + message);
  };
  std::vector<std::vector<double>> bad = faces;
  bad[240000] = {0, 1, 100000};
  bad[150001] = {0, 100000, 1};
  expect_error(bad, "PLY body: face 150001 names vertex 100000, but there are 100000");
  bad[30000] = {5, 6};
  bad[30001] = {1, 2, 3, 4};  // the file keeps the size the header's counts need
  expect_error(bad, "PLY body: face 30000 has 2 vertices");
}

TEST(ReadPly, BigFileWithANonFiniteCoordinateIsRefused) {
  TempDir dir;
  std::vector<std::vector<double>> faces(70000, {0, 1, 2});
  std::string ply = big_ply(false, 70000, faces, false);
  // Vertex 69,999's y (the vertices end where the faces' 70,000 records of 13 bytes begin).
  const std::size_t y = ply.size() - 13 * faces.size() - 8;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(&ply[y], &nan, 4);
  const std::string path = dir.write("nan.ply", ply);
  const Result<Mesh> mesh = read_mesh(path);
  ASSERT_FALSE(mesh.ok());
  EXPECT_EQ(mesh.error().message, path + ": has a vertex with a non-finite coordinate");
}

// Bytes after the last element used to be ignored: a face count one too small dropped a face
// without a word, and two files joined read as the first. The last element ends the file.
TEST(ReadPly, BytesAfterTheLastElementAreRefusedNamingTheOffset) {
  TempDir dir;
  for (const bool big : {false, true}) {
    const std::string ply = binary_square(big);
    for (const std::string& extra :
         {std::string("\n"), std::string(1, '\0'), std::string("ply\n")}) {
      const std::string path = dir.write("after.ply", ply + extra);
      const Result<Mesh> mesh = read_mesh(path);
      ASSERT_FALSE(mesh.ok()) << big << " " << extra.size();
      EXPECT_EQ(mesh.error().message, path + ": " + std::to_string(extra.size()) +
                                          (extra.size() == 1 ? " byte" : " bytes") +
                                          " after the last element ('face'), from byte offset " +
                                          std::to_string(ply.size()) +
                                          " on: a binary PLY file ends with its last element");
    }
  }
  // The same in the parallel reader's blocks: a face count that leaves the last face out.
  std::vector<std::vector<double>> faces(70000, {0, 1, 2});
  std::string big = big_ply(false, 70000, faces, false);
  const std::string count = "element face 70000\n";
  big.replace(big.find(count), count.size(), "element face 69999\n");
  const std::string path = dir.write("one_more.ply", big);
  const Result<Mesh> mesh = read_mesh(path);
  ASSERT_FALSE(mesh.ok());
  EXPECT_EQ(mesh.error().message,
            path + ": 13 bytes after the last element ('face'), from byte offset " +
                std::to_string(big.size() - 13) +
                " on: a binary PLY file ends with its last element");

  // ASCII: blank lines and whitespace after the last element are fine; anything else is refused
  // naming the line.
  const std::string ascii =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  const Result<Mesh> blank = read_mesh(dir.write("blank.ply", ascii + "\n  \t\r\n\n"));
  ASSERT_TRUE(blank.ok()) << blank.error().message;
  EXPECT_EQ(blank->num_triangles(), 1u);
  const std::string more = dir.write("more.ply", ascii + "\n3 0 2 1\n");
  const Result<Mesh> refused = read_mesh(more);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().message,
            more +
                ": PLY body line 6: text after the last element ('face'): '3'; an ASCII PLY "
                "file ends with its last element (blank lines aside)");
}

}  // namespace
}  // namespace lightvol
