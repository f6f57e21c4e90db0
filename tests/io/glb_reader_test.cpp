// The GLB reader: scenes, node transforms (mirrors flip the winding), triangle lists, strips and
// fans, and every structural problem an Error naming the object; instancing is bounded.
#include <array>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <lightvol/core/limits.h>
#include <lightvol/io/detail/glb_reader.h>

namespace lightvol::detail {
namespace {

using Json = nlohmann::json;

// A GLB of `doc` and `bin` (both padded to 4 bytes).
std::string glb(Json doc, std::string bin) {
  bin.resize((bin.size() + 3) & ~std::size_t{3}, '\0');
  if (!doc.contains("buffers")) doc["buffers"] = Json::array({{{"byteLength", bin.size()}}});
  std::string json = doc.dump();
  json.resize((json.size() + 3) & ~std::size_t{3}, ' ');
  std::string out = "glTF";
  const auto put = [&](std::uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
  put(2);
  put(static_cast<std::uint32_t>(28 + json.size() + bin.size()));
  put(static_cast<std::uint32_t>(json.size()));
  put(0x4E4F534Au);
  out += json;
  put(static_cast<std::uint32_t>(bin.size()));
  put(0x004E4942u);
  return out + bin;
}

template <typename T>
std::string bytes_of(const std::vector<T>& values) {
  return std::string(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
}

// A unit tetrahedron, outward (volume 1/6): positions (view 0, accessor 0) and ushort indices
// (view 1, accessor 1) in one mesh, and `nodes` (default: one node naming it).
const std::vector<float> kTetra = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
const std::vector<std::uint16_t> kTetraFaces = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};

Json tetra_doc() {
  return {{"asset", {{"version", "2.0"}}},
          {"scene", 0},
          {"scenes", {{{"nodes", {0}}}}},
          {"nodes", {{{"mesh", 0}}}},
          {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
          {"accessors",
           {{{"bufferView", 0}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}},
            {{"bufferView", 1}, {"componentType", 5123}, {"count", 12}, {"type", "SCALAR"}}}},
          {"bufferViews",
           {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 48}},
            {{"buffer", 0}, {"byteOffset", 48}, {"byteLength", 24}}}}};
}
std::string tetra_bin() { return bytes_of(kTetra) + bytes_of(kTetraFaces); }

Result<DracoMesh> read(const Json& doc, const std::string& bin = tetra_bin()) {
  return read_glb(glb(doc, bin), "t.glb");
}

TEST(GlbReader, ReadsATriangleListAsStored) {
  const Result<DracoMesh> m = read(tetra_doc());
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_EQ(m->mesh.positions, kTetra);
  EXPECT_EQ(m->mesh.indices, std::vector<std::uint32_t>(kTetraFaces.begin(), kTetraFaces.end()));
  EXPECT_DOUBLE_EQ(signed_volume(m->mesh), 1.0 / 6);
  EXPECT_EQ(m->step, 0.0);
}

// translation · rotation · scale, a parent's transform applied to its children, and a mirroring
// scale turning the faces so that the volume stays outward.
TEST(GlbReader, NodeTransformsMoveAndMirrorsFlip) {
  Json doc = tetra_doc();
  doc["nodes"] = {{{"children", {1}}, {"translation", {10, 0, 0}}},
                  {{"mesh", 0},
                   {"scale", {2, 2, 2}},
                   {"rotation", {0, 0, 0.7071067811865476, 0.7071067811865476}}}};
  Result<DracoMesh> m = read(doc);
  ASSERT_TRUE(m.ok()) << m.error().message;
  // Vertex 1 (1, 0, 0): scaled to (2, 0, 0), turned 90° about z to (0, 2, 0), moved to (10, 2, 0).
  EXPECT_NEAR(m->mesh.positions[3], 10, 1e-6);
  EXPECT_NEAR(m->mesh.positions[4], 2, 1e-6);
  EXPECT_NEAR(m->mesh.positions[5], 0, 1e-6);
  EXPECT_NEAR(signed_volume(m->mesh), 8.0 / 6, 1e-6);

  doc["nodes"] = {{{"mesh", 0},
                   {"matrix", {-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 5, 6, 7, 1}}}};  // column-major
  m = read(doc);
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_EQ(m->mesh.vertex(1), (std::array<float, 3>{4, 6, 7}));
  EXPECT_NEAR(signed_volume(m->mesh), 1.0 / 6, 1e-6);  // mirrored, and turned outward again
  EXPECT_EQ(m->mesh.triangle(0), (std::array<std::uint32_t, 3>{0, 1, 2}));
}

// The default scene alone; with no scenes, every mesh once; a mesh named by two nodes twice.
TEST(GlbReader, TheDefaultSceneIsRead) {
  Json doc = tetra_doc();
  doc["scenes"] = {{{"nodes", {0}}}, {{"nodes", {0, 1}}}};
  doc["nodes"] = {{{"mesh", 0}}, {{"mesh", 0}, {"translation", {0, 0, 5}}}};
  doc["scene"] = 1;
  Result<DracoMesh> m = read(doc);
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_EQ(m->mesh.num_triangles(), 8u);
  doc.erase("scene");
  m = read(doc);
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_EQ(m->mesh.num_triangles(), 4u);
  doc.erase("scenes");
  doc.erase("nodes");
  m = read(doc);
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_EQ(m->mesh.num_triangles(), 4u);
}

TEST(GlbReader, StripsAndFans) {
  // A square as a strip (0 1 2 3) and as a fan (0 1 2 3): two counter-clockwise triangles each.
  const std::vector<float> square = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  Json doc = tetra_doc();
  doc["accessors"] = {{{"bufferView", 0}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}}};
  doc["bufferViews"] = {{{"buffer", 0}, {"byteLength", 48}}};
  doc["meshes"][0]["primitives"] = {{{"attributes", {{"POSITION", 0}}}, {"mode", 5}}};
  Result<DracoMesh> m = read(doc, bytes_of(square));
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_EQ(m->mesh.indices, (std::vector<std::uint32_t>{0, 1, 2, 1, 3, 2}));
  const std::vector<float> fan = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  doc["meshes"][0]["primitives"][0]["mode"] = 6;
  m = read(doc, bytes_of(fan));
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_EQ(m->mesh.indices, (std::vector<std::uint32_t>{1, 2, 0, 2, 3, 0}));
}

TEST(GlbReader, BadDocumentsAreErrorsNamingTheObject) {
  const struct {
    std::function<void(Json&)> edit;
    std::string message;
  } cases[] = {
      {[](Json& d) { d["nodes"][0]["children"] = {0}; },
       "node 0 is reached twice from scene 0: the nodes do not form trees"},
      {[](Json& d) {
         d["scenes"][0]["nodes"] = {0, 0};
       },
       "node 0 is reached twice from scene 0: the nodes do not form trees"},
      {[](Json& d) { d["nodes"][0]["mesh"] = 3; }, "nodes 0: 'mesh' names no element of 'meshes'"},
      {[](Json& d) { d["scene"] = 2; }, "the document: 'scene' names no element of 'scenes'"},
      {[](Json& d) { d["meshes"][0]["primitives"][0]["mode"] = 1; },
       "mesh 0 primitive 0: mode 1 is not triangles (4), a strip (5) or a fan (6)"},
      {[](Json& d) { d["accessors"][1]["count"] = 11; },
       "mesh 0 primitive 0: 11 vertices do not make whole triangles"},
      {[](Json& d) { d["accessors"][1]["count"] = 13; },
       "accessor 1 runs past the end of its buffer view"},
      {[](Json& d) { d["accessors"][1]["componentType"] = 5122; },
       "mesh 0 primitive 0: indices are not unsigned integer scalars"},
      {[](Json& d) { d["accessors"][0]["componentType"] = 5123; },
       "mesh 0 primitive 0: POSITION is not a float VEC3 accessor"},
      {[](Json& d) { d["bufferViews"][1]["byteLength"] = 28; },
       "bufferViews 1 lies outside buffer 0"},
      {[](Json& d) {
         d["nodes"][0]["matrix"] = {1, 2, 3};
       },
       "node 0: 'matrix' is not 16 numbers"},
      {[](Json& d) {
         d["nodes"][0]["rotation"] = {0, 0, 0, 0};
       },
       "node 0: 'rotation' is not a rotation"},
      {[](Json& d) { d["meshes"][0]["primitives"][0].erase("attributes"); },
       "mesh 0 primitive 0 has no attributes"},
  };
  for (const auto& c : cases) {
    Json doc = tetra_doc();
    c.edit(doc);
    const Result<DracoMesh> m = read(doc);
    ASSERT_FALSE(m.ok()) << c.message;
    EXPECT_EQ(m.error().message, "t.glb: glTF binary: " + c.message);
  }
  // An index past the positions names the primitive, the index and the count.
  std::vector<std::uint16_t> faces = kTetraFaces;
  faces[7] = 4;
  const Result<DracoMesh> m = read(tetra_doc(), bytes_of(kTetra) + bytes_of(faces));
  ASSERT_FALSE(m.ok());
  EXPECT_EQ(
      m.error().message,
      "t.glb: glTF binary: mesh 0 primitive 0: index 7 is 4, but its attributes have 4 elements");
}

// Nodes cost bytes, instances of a mesh do not: 10,000 nodes naming a 10,000-triangle strip
// would be 10^8 triangles from 140 KB, so the reader stops at 256 triangles per byte.
TEST(GlbReader, InstancingIsBoundedByTheFileSize) {
  std::vector<std::uint16_t> strip(10002);
  for (std::size_t i = 0; i < strip.size(); ++i) strip[i] = static_cast<std::uint16_t>(i % 4);
  Json doc = tetra_doc();
  doc["accessors"][1]["count"] = strip.size();
  doc["bufferViews"][1]["byteLength"] = 2 * strip.size();
  doc["meshes"][0]["primitives"][0]["mode"] = 5;
  const auto instances = [&](int count) {
    doc["nodes"] = Json::array();
    doc["scenes"][0]["nodes"] = Json::array();
    for (int n = 0; n < count; ++n) {
      doc["nodes"].push_back({{"mesh", 0}});
      doc["scenes"][0]["nodes"].push_back(n);
    }
  };
  instances(10000);
  const Result<DracoMesh> m = read(doc, bytes_of(kTetra) + bytes_of(strip));
  ASSERT_FALSE(m.ok());
  EXPECT_NE(m.error().message.find("10000 mesh instances add up to 100000000 triangles and 40000 "
                                   "vertices, more than 256 per byte"),
            std::string::npos)
      << m.error().message;
  // A hundred instances are fine.
  instances(100);
  const Result<DracoMesh> few = read(doc, bytes_of(kTetra) + bytes_of(strip));
  ASSERT_TRUE(few.ok()) << few.error().message;
  EXPECT_EQ(few->mesh.num_triangles(), 100u * 10000);
  // ... within the memory budget (--max-memory).
  const std::uint64_t budget = memory_budget();
  set_memory_budget(16 << 20);
  const Result<DracoMesh> over = read(doc, bytes_of(kTetra) + bytes_of(strip));
  set_memory_budget(budget);
  ASSERT_FALSE(over.ok());
  EXPECT_EQ(over.error().message.rfind(
                "t.glb: assembling 1000000 triangles needs about 22.9 MiB of memory", 0),
            0u)
      << over.error().message;
}

// The header's length is the file's (glTF 2.0): bytes after the last chunk were ignored before.
TEST(GlbReader, BytesAfterTheLastChunkAreRefused) {
  const std::string file = glb(tetra_doc(), tetra_bin());
  ASSERT_TRUE(read_glb(file, "t.glb").ok());
  const Result<DracoMesh> longer = read_glb(file + std::string(4, '\0'), "t.glb");
  ASSERT_FALSE(longer.ok());
  EXPECT_EQ(longer.error().message, "t.glb: glTF binary: header claims " +
                                        std::to_string(file.size()) + " bytes, the file has " +
                                        std::to_string(file.size() + 4));
}

}  // namespace
}  // namespace lightvol::detail
