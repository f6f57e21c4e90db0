// read_mesh: every format write_mesh writes comes back with the same triangles at the same
// positions; polygons are fan-triangulated; junk, empty, truncated and missing files are Errors
// naming the file.
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <lightvol/check/check.h>
#include <lightvol/export/export.h>
#include <lightvol/io/mesh_reader.h>
#include <lightvol/volume/static_volume.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

using test::TempDir;

Mesh sample_volume() {
  const Light light = test::light_from_json(test::spot_json());
  const DepthImage depth = test::make_depth(6, 5, [](int c, int r) {
    return (c == 2 && r >= 1 && r <= 3) ? 0.95f : 0.98f - 0.001f * static_cast<float>(c);
  });
  Result<Mesh> mesh = build_static_volume(light, depth, {}, "test.exr");
  EXPECT_TRUE(mesh.ok());
  return *mesh;
}

// Same triangle count and, triangle by triangle, the same corner positions (vertex numbering may
// differ: STL stores corners, and welding numbers vertices in order of first use).
::testing::AssertionResult same_triangles(const Mesh& a, const Mesh& b) {
  if (a.num_vertices() != b.num_vertices())
    return ::testing::AssertionFailure()
           << a.num_vertices() << " vs " << b.num_vertices() << " vertices";
  if (a.num_triangles() != b.num_triangles())
    return ::testing::AssertionFailure()
           << a.num_triangles() << " vs " << b.num_triangles() << " triangles";
  for (std::size_t t = 0; t < a.num_triangles(); ++t)
    for (int k = 0; k < 3; ++k)
      if (a.vertex(a.triangle(t)[k]) != b.vertex(b.triangle(t)[k]))
        return ::testing::AssertionFailure() << "triangle " << t << " corner " << k << " moved";
  return ::testing::AssertionSuccess();
}

struct Case {
  const char* name;
  bool ascii;
};

class RoundTrip : public ::testing::TestWithParam<Case> {};

TEST_P(RoundTrip, SameTrianglesAndPositions) {
  TempDir dir;
  const Mesh mesh = sample_volume();
  const std::string path = dir.file(GetParam().name);
  ExportOptions options;
  options.ascii = GetParam().ascii;
  ASSERT_TRUE(write_mesh(path, mesh, options).ok());
  Result<Mesh> back = read_mesh(path);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_TRUE(same_triangles(mesh, *back));
  const Light light = test::light_from_json(test::spot_json());
  const CheckReport report = check_volume_linear(*back, &light);
  EXPECT_TRUE(report.valid()) << report.first_failure();
}

INSTANTIATE_TEST_SUITE_P(Formats, RoundTrip,
                         ::testing::Values(Case{"v.ply", false}, Case{"v_ascii.ply", true},
                                           Case{"v.obj", false}, Case{"v.off", false},
                                           Case{"v.stl", false}, Case{"v_ascii.stl", true},
                                           Case{"v.glb", false}, Case{"V.PLY", false}),
                         [](const auto& param_info) {
                           std::string n = param_info.param.name;
                           for (char& c : n)
                             c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
                           return n;
                         });

// Draco quantizes positions: same counts, positions within the quantization step, still sound.
TEST(ReadMesh, DracoFormatsKeepCountsAndStaySound) {
  TempDir dir;
  const Mesh mesh = sample_volume();
  const Light light = test::light_from_json(test::spot_json());
  const Bounds box = bounding_box(mesh);
  double extent = 0;
  for (int k = 0; k < 3; ++k) extent = std::max(extent, box.max[k] - box.min[k]);
  for (const char* name : {"v.drc", "v_draco.glb"}) {
    ExportOptions options;
    options.draco = std::string(name) == "v_draco.glb";
    options.draco_bits = 20;
    const std::string path = dir.file(name);
    ASSERT_TRUE(write_mesh(path, mesh, options).ok()) << name;
    Result<Mesh> back = read_mesh(path);
    ASSERT_TRUE(back.ok()) << back.error().message;
    EXPECT_EQ(back->num_triangles(), mesh.num_triangles()) << name;
    EXPECT_EQ(back->num_vertices(), mesh.num_vertices()) << name;
    EXPECT_NEAR(signed_volume(*back), signed_volume(mesh), 1e-4 * signed_volume(mesh)) << name;
    const Bounds b = bounding_box(*back);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(b.min[k], box.min[k], extent * 1e-5) << name;
      EXPECT_NEAR(b.max[k], box.max[k], extent * 1e-5) << name;
    }
    const CheckReport report = check_volume_linear(*back, &light);
    EXPECT_TRUE(report.valid()) << name << ": " << report.first_failure();
  }
}

// Draco's default 16 bits move a spot volume's apex off the light and a directional volume's cap
// off the near plane. What `build` writes with the light must still pass `check --light`: the
// reader reports the file's quantization step, and the light proof allows for it (without it,
// the same files fail).
TEST(ReadMesh, DracoFilesReportTheirQuantizationStepAndStaySoundSeenFromTheLight) {
  TempDir dir;
  const DepthImage depth = test::make_depth(40, 30, [](int c, int r) {
    return (c > 10 && c < 20 && r > 5) ? 0.9f : 0.97f + 0.0005f * static_cast<float>(r);
  });
  // Lights off the origin, whose coordinates are no multiples of the grid's step.
  const std::string at =
      R"("position": [0.37, 4.17, -0.21], "direction": [0, -1, 0], "up": [0, 0, -1], )";
  for (const std::string& json :
       {R"({"type": "spot", )" + at +
            R"("fov_y_deg": 60, "near": 0.1, "far": 30, "depth": "window"})",
        R"({"type": "directional", )" + at +
            R"("ortho": [-5, 5, -4, 4], "near": 0, "far": 6, "depth": "window"})"}) {
    const Light light = test::light_from_json(json);
    Result<Mesh> mesh = build_static_volume(light, depth, {}, "test.exr");
    ASSERT_TRUE(mesh.ok()) << mesh.error().message;
    const Bounds box = bounding_box(*mesh);
    double extent = 0;
    for (int k = 0; k < 3; ++k) extent = std::max(extent, box.max[k] - box.min[k]);
    for (const char* name : {"v.drc", "v_draco.glb"}) {
      ExportOptions options;
      options.draco = std::string(name) == "v_draco.glb";
      options.light = &light;
      const std::string path = dir.file(name);
      ASSERT_TRUE(write_mesh(path, *mesh, options).ok()) << name;
      double step = -1;
      Result<Mesh> back = read_mesh(path, &step);
      ASSERT_TRUE(back.ok()) << back.error().message;
      // Draco's grid: the largest extent over 2^16 − 1 steps.
      EXPECT_NEAR(step, extent / 65535, 1e-3 * extent / 65535) << name;
      const CheckReport allowed = check_volume_linear(*back, &light, 5, step);
      EXPECT_TRUE(allowed.valid()) << name << ": " << allowed.first_failure();
      EXPECT_FALSE(check_volume_linear(*back, &light).valid()) << name << ": " << json;
    }
  }
  double step = -1;
  ASSERT_TRUE(write_mesh(dir.file("v.ply"), sample_volume()).ok());
  ASSERT_TRUE(read_mesh(dir.file("v.ply"), &step).ok());
  EXPECT_EQ(step, 0.0);
}

// A GLB whose JSON chunk is `edit`ed; the BIN chunk stays as it was.
std::string edit_glb(const std::string& glb, const std::function<void(nlohmann::json&)>& edit) {
  std::uint32_t json_length = 0;
  std::memcpy(&json_length, glb.data() + 12, 4);
  nlohmann::json doc = nlohmann::json::parse(glb.substr(20, json_length));
  edit(doc);
  std::string json = doc.dump();
  json.resize((json.size() + 3) & ~std::size_t{3}, ' ');
  const std::string bin = glb.substr(20 + json_length);
  std::string out = "glTF";
  const auto put = [&](std::uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
  put(2);
  put(static_cast<std::uint32_t>(20 + json.size() + bin.size()));
  put(static_cast<std::uint32_t>(json.size()));
  put(0x4E4F534Au);
  return out + json + bin;
}

// A GLB names other files through 'uri's (buffers, images): none is opened, and everything but
// the positions and faces (materials, textures, normals) is dropped before Draco sees the file.
TEST(ReadMesh, GlbIsReadForItsGeometryAloneAndOpensNoOtherFile) {
  TempDir dir;
  const Mesh mesh = sample_volume();
  ASSERT_TRUE(write_mesh(dir.file("v.glb"), mesh).ok());
  std::ifstream in(dir.file("v.glb"), std::ios::binary);
  const std::string glb((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // A file that exists, is readable and is not an image: decoding it would fail the read.
  const std::string bait = dir.write("bait.png", "not a png");
  const std::string edited = edit_glb(glb, [&](nlohmann::json& doc) {
    doc["buffers"][0]["uri"] = bait;
    doc["images"] = {{{"uri", bait}}, {{"uri", "data:image/png;base64,AAAA"}}};
    doc["textures"] = {{{"source", 0}}, {{"source", 1}}};
    doc["materials"] = {{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}};
    doc["meshes"][0]["primitives"][0]["material"] = 0;
    doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = 99;  // names no accessor
  });
  const Result<Mesh> back = read_mesh(dir.write("uri.glb", edited));
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_TRUE(same_triangles(mesh, *back));
}

// Draco-compressed primitives: their data is Draco's to check, the references around it are
// lightvol's (an 'indices' naming a missing accessor and a POSITION id naming no attribute of the
// compressed data both crashed Draco's glTF decoder).
TEST(ReadMesh, DracoGlbReferencesAreChecked) {
  TempDir dir;
  ExportOptions options;
  options.draco = true;
  ASSERT_TRUE(write_mesh(dir.file("d.glb"), sample_volume(), options).ok());
  std::ifstream in(dir.file("d.glb"), std::ios::binary);
  const std::string glb((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_TRUE(read_mesh(dir.file("d.glb")).ok());
  const auto primitive = [](nlohmann::json& doc) -> nlohmann::json& {
    return doc["meshes"][0]["primitives"][0];
  };
  const struct {
    std::function<void(nlohmann::json&)> edit;
    std::string message;
  } cases[] = {
      {[&](nlohmann::json& d) { primitive(d)["indices"] = 77; },
       "mesh 0 primitive 0: 'indices' names no element of 'accessors'"},
      {[&](nlohmann::json& d) {
         primitive(d)["extensions"]["KHR_draco_mesh_compression"]["attributes"]["POSITION"] = 5;
       },
       "mesh 0 primitive 0: KHR_draco_mesh_compression data: no attribute has the POSITION id 5"},
      {[&](nlohmann::json& d) {
         primitive(d)["extensions"]["KHR_draco_mesh_compression"]["bufferView"] = 99;
       },
       "mesh 0 primitive 0 KHR_draco_mesh_compression: 'bufferView' names no element of "
       "'bufferViews'"},
      {[&](nlohmann::json& d) {
         d["accessors"][primitive(d)["attributes"]["POSITION"].get<int>()]["type"] = "VEC2";
       },
       "mesh 0 primitive 0: POSITION is not a float VEC3 accessor"},
  };
  for (const auto& c : cases) {
    const std::string path = dir.write("bad.glb", edit_glb(glb, c.edit));
    const Result<Mesh> mesh = read_mesh(path);
    ASSERT_FALSE(mesh.ok()) << c.message;
    EXPECT_EQ(mesh.error().message, path + ": glTF binary: " + c.message);
  }
}

// Many compressed primitives are decoded together (in one child process): each lands in its own
// instance, and a bad one among them is the error, named, however many precede it.
TEST(ReadMesh, ManyDracoGlbPrimitivesAreDecodedInOrder) {
  TempDir dir;
  ExportOptions options;
  options.draco = true;
  const Mesh volume = sample_volume();
  ASSERT_TRUE(write_mesh(dir.file("d.glb"), volume, options).ok());
  std::ifstream in(dir.file("d.glb"), std::ios::binary);
  const std::string glb((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  constexpr int kMeshes = 120;
  // kMeshes meshes, each with the compressed primitive twice (the same data, decoded once), one
  // node each, moved apart so that nothing is welded between them.
  const auto many = [&](nlohmann::json& d) {
    const nlohmann::json primitive = d["meshes"][0]["primitives"][0];
    d["meshes"] = nlohmann::json::array();
    d["nodes"] = nlohmann::json::array();
    d["scenes"] = {{{"nodes", nlohmann::json::array()}}};
    d["scene"] = 0;
    for (int m = 0; m < kMeshes; ++m) {
      d["meshes"].push_back({{"primitives", {primitive, primitive}}});
      d["nodes"].push_back({{"mesh", m}, {"translation", {100.0 * m, 0, 0}}});
      d["scenes"][0]["nodes"].push_back(m);
    }
  };
  const Result<Mesh> mesh = read_mesh(dir.write("many.glb", edit_glb(glb, many)));
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  EXPECT_EQ(mesh->num_triangles(), 2 * kMeshes * volume.num_triangles());
  EXPECT_EQ(mesh->num_vertices(), kMeshes * volume.num_vertices());  // each pair welds to one
  const std::string bad = dir.write("bad.glb", edit_glb(glb, [&](nlohmann::json& d) {
                                      many(d);
                                      d["meshes"][97]["primitives"][1]["extensions"]
                                       ["KHR_draco_mesh_compression"]["attributes"]["POSITION"] = 5;
                                    }));
  const Result<Mesh> broken = read_mesh(bad);
  ASSERT_FALSE(broken.ok());
  EXPECT_EQ(broken.error().message,
            bad +
                ": glTF binary: mesh 97 primitive 1: KHR_draco_mesh_compression data: no attribute "
                "has the POSITION id 5");
}

// Draco's decoders trust their data (fuzzing an instrumented Draco 1.5.5 found dozens of inputs
// with undefined behaviour in minutes); they run in a child process with limits. Found so: 52
// bytes for which Draco allocates 2.8 GB; found by fuzz_mesh on the uninstrumented library: 87
// bytes for which the reader took 8.9 GB and 7 s before the child process.
TEST(ReadMesh, DracoRunsWithinLimitsOfItsOwn) {
  TempDir dir;
  for (const auto& [name, bytes] : {std::pair{"regression_drc_52_bytes_allocate_gigabytes", 52},
                                    std::pair{"regression_drc_edgebreaker_reserve", 87}}) {
    const std::string path =
        dir.write(std::string(name) + ".drc", test::fuzz_regression_file("mesh", name));
    const Result<Mesh> mesh = read_mesh(path);
    ASSERT_FALSE(mesh.ok());
#if defined(__SANITIZE_ADDRESS__)
    // No address-space limit under AddressSanitizer: Draco gets its gigabytes, then fails or is
    // stopped at its processor time.
    EXPECT_EQ(mesh.error().message.rfind(path + ": ", 0), 0u) << mesh.error().message;
#else
    const std::string limit = bytes == 52 ? "256.2 MiB" : "256.3 MiB";
    EXPECT_EQ(mesh.error().message, path + ": Draco's decoder ran out of memory (its limit is " +
                                        limit + "; no Draco mesh of " + std::to_string(bytes) +
                                        " bytes needs that much: the data is corrupt)");
#endif
  }
}

TEST(ReadMesh, PolygonsAreFanTriangulated) {
  TempDir dir;
  // A cube of six quads, and one pentagon-free OBJ with negative (relative) indices.
  const std::string off =
      dir.write("cube.off",
                "OFF\n8 6 0\n"
                "-1 -1 -1\n1 -1 -1\n-1 1 -1\n1 1 -1\n-1 -1 1\n1 -1 1\n-1 1 1\n1 1 1\n"
                "4 0 2 3 1\n4 4 5 7 6\n4 0 1 5 4\n4 2 6 7 3\n4 0 4 6 2\n4 1 3 7 5\n");
  Result<Mesh> cube = read_mesh(off);
  ASSERT_TRUE(cube.ok()) << cube.error().message;
  EXPECT_EQ(cube->num_triangles(), 12u);
  EXPECT_EQ(cube->num_vertices(), 8u);
  EXPECT_EQ(cube->triangle(0), (std::array<std::uint32_t, 3>{0, 2, 3}));
  EXPECT_EQ(cube->triangle(1), (std::array<std::uint32_t, 3>{0, 3, 1}));
  EXPECT_DOUBLE_EQ(signed_volume(*cube), 8.0);

  const std::string obj = dir.write("quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
  Result<Mesh> quad = read_mesh(obj);
  ASSERT_TRUE(quad.ok()) << quad.error().message;
  EXPECT_EQ(quad->num_triangles(), 2u);
}

// Before: comment lines before the keyword (as CGAL writes them) made "not an OFF file", and the
// header variants 4OFF and nOFF were refused. Geomview's OFF: comments anywhere, the keyword
// optional, [ST][C][N][4][n]OFF.
TEST(ReadMesh, OffAsGeomviewDefinesIt) {
  TempDir dir;
  const std::string tetra_vertices = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
  const std::string tetra_faces = "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
  const auto expect_tetra = [&](const std::string& name, const std::string& text, double scale) {
    Result<Mesh> mesh = read_mesh(dir.write(name, text));
    ASSERT_TRUE(mesh.ok()) << name << ": " << mesh.error().message;
    EXPECT_EQ(mesh->num_triangles(), 4u) << name;
    EXPECT_EQ(mesh->num_vertices(), 4u) << name;
    EXPECT_NEAR(signed_volume(*mesh), scale * scale * scale / 6, 1e-6) << name;
  };
  expect_tetra("cgal.off",
               "# Output of a CGAL tool\n#\nOFF\n4 4 0\n\n# vertices\n" + tetra_vertices +
                   "\n# faces\n" + tetra_faces,
               1);
  expect_tetra("nokeyword.off", "4 4 6\n" + tetra_vertices + tetra_faces, 1);
  expect_tetra("sameline.off", "OFF 4 4 6 # counts\n" + tetra_vertices + tetra_faces, 1);
  expect_tetra("coff.off",
               "COFF\n4 4 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n"
               "0 0 1 9 9 9 255\n3 0 2 1 1 0 0\n3 0 1 3\n3 0 3 2 0.5 0.5 0.5 1\n3 1 2 3 7\n",
               1);
  expect_tetra("stcnoff.off",
               "STCNOFF\n4 4 0\n0 0 0 0 0 1 1 1 1 1 0 0\n1 0 0 0 0 1 1 1 1 1 0 1\n"
               "0 1 0 0 0 1 1 1 1 1 1 0\n0 0 1 0 0 1 1 1 1 1 1 1\n" +
                   tetra_faces,
               1);
  expect_tetra("homogeneous.off", "4OFF\n4 4 0\n0 0 0 2\n1 0 0 2\n0 1 0 2\n0 0 1 2\n" + tetra_faces,
               0.5);
  expect_tetra("ndim.off", "nOFF\n3\n4 4 0\n" + tetra_vertices + tetra_faces, 1);
  expect_tetra("4ndim.off", "4nOFF 3 4 4 0\n0 0 0 1\n2 0 0 2\n0 3 0 3\n0 0 2 2\n" + tetra_faces, 1);
  const auto expect_refused = [&](const std::string& name, const std::string& text,
                                  const std::string& why) {
    Result<Mesh> mesh = read_mesh(dir.write(name, text));
    ASSERT_FALSE(mesh.ok()) << name;
    EXPECT_NE(mesh.error().message.find(why), std::string::npos) << mesh.error().message;
  };
  expect_refused("2d.off", "nOFF 2\n3 1 0\n0 0\n1 0\n0 1\n3 0 1 2\n",
                 "only 3-dimensional OFF makes a triangle mesh");
  expect_refused("inf.off", "4OFF\n4 4 0\n0 0 0 0\n1 0 0 1\n0 1 0 1\n0 0 1 1\n" + tetra_faces,
                 "homogeneous coordinate 0");
  expect_refused("xoff.off", "XOFF\n4 4 0\n" + tetra_vertices + tetra_faces,
                 "'XOFF' is not an OFF keyword");
  expect_refused("comments.off", "# just a comment\nhello\n", "not an OFF file");
}

TEST(ReadMesh, BadFilesAreErrorsNamingTheFile) {
  TempDir dir;
  const auto expect_error = [](const std::string& path, const std::string& what) {
    Result<Mesh> mesh = read_mesh(path);
    ASSERT_FALSE(mesh.ok()) << path;
    EXPECT_NE(mesh.error().message.find(path), std::string::npos) << mesh.error().message;
    EXPECT_NE(mesh.error().message.find(what), std::string::npos) << mesh.error().message;
  };
  expect_error(dir.file("missing.ply"), "no such file");
  expect_error(dir.write("empty.obj", ""), "empty file");
  expect_error(dir.write("junk.ply", "this is not a mesh\n"), "not a PLY file");
  expect_error(dir.write("junk.off", "hello world\n1 2 3\n"), "not an OFF file");
  expect_error(dir.write("junk.stl", std::string(200, '\x7f')), "not an STL file");
  expect_error(dir.write("junk.obj", std::string("v 1 2 3\n\0\0\0", 11)), "not an OBJ file");
  expect_error(dir.write("junk.drc", "DRACO but not really"), "not a Draco mesh");
  expect_error(dir.write("junk.glb", "glTF but truncated"), "glTF");
  // Found by fuzz_mesh: Draco's glTF decoder copied attribute values past their end for an index
  // beyond the attribute's count, and crashed on a scene naming node 5 of 1.
  expect_error(dir.write("index.glb",
                         test::fuzz_regression_file("mesh", "regression_glb_index_past_attribute")),
               "mesh 0 primitive 0: index 60 is 46, but its attributes have 17 elements");
  // Found by fuzz_mesh: a Draco file whose POSITION has 7 components was copied into 3 floats.
  expect_error(dir.write("seven.drc",
                         test::fuzz_regression_file("mesh", "regression_drc_position_components")),
               "seven.drc: POSITION has 7 components, not 3");
  // Found by fuzz_mesh: a Draco file with a bool POSITION was read as bools holding other bytes.
  expect_error(
      dir.write("bool.drc", test::fuzz_regression_file("mesh", "regression_drc_bool_position")),
      "bool.drc: POSITION is not of a number type");
  // Found by fuzz_mesh: a buffer view inside the BIN chunk but past buffer 0's byteLength made
  // Draco's glTF decoder read freed memory.
  expect_error(
      dir.write("view.glb", test::fuzz_regression_file("mesh", "regression_glb_view_past_buffer")),
      "glTF binary: bufferViews 1 lies outside buffer 0");
  expect_error(dir.write("node.glb",
                         test::fuzz_regression_file("mesh", "regression_glb_node_names_no_mesh")),
               "glTF binary: scenes 0: 'nodes' names no element of 'nodes'");
  // Found by fuzz_mesh: OpenMesh's OBJ reader aborted (an assertion) on a face vertex "/1".
  expect_error(dir.write("slash.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf /1 2 3\n"),
               "OBJ line 4: face vertex '/1' is not v, v/t, v//n or v/t/n");
  expect_error(dir.write("mesh.xyz", "1 2 3\n"), "unknown mesh format");
  expect_error(dir.write("points.obj", "v 0 0 0\nv 1 0 0\n"), "no triangles");
  expect_error(dir.write("bad_index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"),
               "bad_index.off");
  expect_error(dir.write("huge.off", "OFF\n2000000000 1 0\n0 0 0\n"), "huge.off");
  expect_error(dir.write("huge.ply",
                         "ply\nformat ascii 1.0\nelement vertex 4000000000\n"
                         "property float x\nproperty float y\nproperty float z\n"
                         "element face 1\nproperty list uchar int vertex_indices\n"
                         "end_header\n0 0 0\n"),
               "huge.ply");
  expect_error(dir.write("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"),
               "OBJ line 2: 'nan' is not a coordinate");

  // A binary PLY cut short: the header promises more than the body holds.
  const Mesh mesh = sample_volume();
  const std::string ply = dir.file("cut.ply");
  ASSERT_TRUE(write_mesh(ply, mesh).ok());
  std::ifstream in(ply, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  dir.write("cut.ply", bytes.substr(0, bytes.size() / 2));
  expect_error(ply, "cut.ply");
}

}  // namespace
}  // namespace lightvol
