// Every export format, read back with an independent reader and compared with what was written.
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <numbers>

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <draco/compression/decode.h>
#include <draco/io/gltf_decoder.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <lightvol/export/export.h>
#include <lightvol/io/mesh_reader.h>
#include <lightvol/volume/static_volume.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

using test::slurp;

using TriMesh = OpenMesh::TriMesh_ArrayKernelT<>;

Mesh sample_volume() {
  const Light light = test::light_from_json(test::spot_json("linear", 1.2));
  const DepthImage d = test::make_depth(7, 5, [](int c, int r) {
    return (c >= 2 && c <= 4 && r >= 1 && r <= 3) ? 2.0f : 3.5f + 0.1f * static_cast<float>(c);
  });
  Result<Mesh> m = build_static_volume(light, d, {}, "d");
  EXPECT_TRUE(m.ok());
  return *m;
}

Mesh from_openmesh(const std::string& path) {
  TriMesh tm;
  OpenMesh::IO::Options opt;
  EXPECT_TRUE(OpenMesh::IO::read_mesh(tm, path, opt)) << path;
  Mesh m;
  for (const auto& v : tm.vertices()) {
    const auto p = tm.point(v);
    m.positions.insert(m.positions.end(), {p[0], p[1], p[2]});
  }
  for (const auto& f : tm.faces())
    for (const auto& v : f.vertices()) m.indices.push_back(static_cast<std::uint32_t>(v.idx()));
  return m;
}

Mesh from_draco_mesh(const draco::Mesh& dm) {
  Mesh m;
  const auto* pos = dm.GetNamedAttribute(draco::GeometryAttribute::POSITION);
  m.positions.resize(3 * dm.num_points());
  for (draco::PointIndex p(0); p < dm.num_points(); ++p)
    pos->GetMappedValue(p, &m.positions[3 * p.value()]);
  for (draco::FaceIndex f(0); f < dm.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) m.indices.push_back(dm.face(f)[k].value());
  return m;
}

// Same triangles over the same positions, whatever the vertex order: compare the sorted lists
// of triangles written as position triples, rotated to start at their smallest vertex.
using Tri = std::array<std::array<float, 3>, 3>;
std::vector<Tri> triangle_soup(const Mesh& m) {
  std::vector<Tri> soup;
  for (std::size_t t = 0; t < m.num_triangles(); ++t) {
    const auto [a, b, c] = m.triangle(t);
    Tri tri{m.vertex(a), m.vertex(b), m.vertex(c)};
    const auto first = std::min_element(tri.begin(), tri.end()) - tri.begin();
    std::rotate(tri.begin(), tri.begin() + first, tri.end());
    soup.push_back(tri);
  }
  std::sort(soup.begin(), soup.end());
  return soup;
}

TEST(Export, PlyBinaryAndAsciiRoundTripExactly) {
  test::TempDir dir;
  const Mesh m = sample_volume();
  for (bool ascii : {false, true}) {
    const std::string path = dir.file(ascii ? "a.ply" : "b.ply");
    ExportOptions o;
    o.ascii = ascii;
    ASSERT_TRUE(write_mesh(path, m, o).ok());
    const Mesh back = from_openmesh(path);
    EXPECT_EQ(back.positions, m.positions);
    EXPECT_EQ(back.indices, m.indices);
  }
  // Binary layout pinned: header, then 12 bytes per vertex and 13 per face.
  const std::string bytes = slurp(dir.file("b.ply"));
  const auto end = bytes.find("end_header\n");
  ASSERT_NE(end, std::string::npos);
  EXPECT_EQ(bytes.size() - (end + 11), 12 * m.num_vertices() + 13 * m.num_triangles());
  EXPECT_NE(bytes.find("format binary_little_endian 1.0"), std::string::npos);
}

TEST(Export, ObjOffStlRoundTrip) {
  test::TempDir dir;
  const Mesh m = sample_volume();
  for (const char* name : {"m.obj", "m.off", "m.stl", "a.stl"}) {
    SCOPED_TRACE(name);
    ExportOptions o;
    o.ascii = std::string(name) == "a.stl";
    ASSERT_TRUE(write_mesh(dir.file(name), m, o).ok());
    const Mesh back = weld_identical_positions(from_openmesh(dir.file(name)));
    EXPECT_EQ(back.num_vertices(), m.num_vertices());
    EXPECT_EQ(back.num_triangles(), m.num_triangles());
    EXPECT_EQ(triangle_soup(back), triangle_soup(m));
  }
}

TEST(Export, DracoDecodesToAClosedVolumeWithinQuantization) {
  test::TempDir dir;
  const Mesh m = sample_volume();
  ASSERT_TRUE(write_mesh(dir.file("m.drc"), m).ok());
  const std::string bytes = slurp(dir.file("m.drc"));
  draco::DecoderBuffer buffer;
  buffer.Init(bytes.data(), bytes.size());
  draco::Decoder decoder;
  auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
  ASSERT_TRUE(decoded.ok());
  const Mesh back = weld_identical_positions(from_draco_mesh(*decoded.value()));
  EXPECT_EQ(back.num_triangles(), m.num_triangles());
  EXPECT_EQ(back.num_vertices(), m.num_vertices());
  EXPECT_TRUE(test::is_closed_and_oriented(back));
  // 16 bits over the bounding box's largest side.
  const Bounds b = bounding_box(m);
  const double extent = std::max({b.max[0] - b.min[0], b.max[1] - b.min[1], b.max[2] - b.min[2]});
  EXPECT_NEAR(signed_volume(back), signed_volume(m), 1e-3 * signed_volume(m));
  const Bounds bb = bounding_box(back);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(bb.min[k], b.min[k], extent / 65535 * 2);
}

TEST(Export, GlbPlainAndDracoCompressed) {
  test::TempDir dir;
  const Mesh m = sample_volume();
  for (bool compressed : {false, true}) {
    ExportOptions o;
    o.draco = compressed;
    const std::string path = dir.file(compressed ? "c.glb" : "p.glb");
    ASSERT_TRUE(write_mesh(path, m, o).ok());
    const std::string bytes = slurp(path);
    ASSERT_GE(bytes.size(), 12u);
    EXPECT_EQ(bytes.substr(0, 4), "glTF");
    EXPECT_EQ(bytes.find("KHR_draco_mesh_compression") != std::string::npos, compressed);
    draco::DecoderBuffer buffer;
    buffer.Init(bytes.data(), bytes.size());
    draco::GltfDecoder decoder;
    auto decoded = decoder.DecodeFromBuffer(&buffer);
    ASSERT_TRUE(decoded.ok()) << decoded.status().error_msg_string();
    const Mesh back = weld_identical_positions(from_draco_mesh(*decoded.value()));
    EXPECT_EQ(back.num_triangles(), m.num_triangles());
    EXPECT_TRUE(test::is_closed_and_oriented(back));
    if (!compressed) {
      EXPECT_EQ(triangle_soup(back), triangle_soup(m));
    }
  }
}

// The JSON chunk of a GLB file's bytes.
nlohmann::json glb_json(const std::string& bytes) {
  std::uint32_t length = 0;
  std::memcpy(&length, bytes.data() + 12, 4);
  return nlohmann::json::parse(bytes.substr(20, length));
}

// Rotates v by the unit quaternion q = (x, y, z, w).
Vec3d rotate(const nlohmann::json& q, Vec3d v) {
  const Vec3d u{q[0].get<double>(), q[1].get<double>(), q[2].get<double>()};
  const double w = q[3].get<double>();
  return 2 * dot(u, v) * u + (w * w - dot(u, u)) * v + 2 * w * cross(u, v);
}

TEST(Export, GlbCarriesItsLightAndBufferTargets) {
  test::TempDir dir;
  const Mesh m = sample_volume();
  const Light spot = test::light_from_json(test::spot_json("linear", 1.2));
  for (bool compressed : {false, true}) {
    SCOPED_TRACE(compressed ? "draco" : "plain");
    ExportOptions o;
    o.draco = compressed;
    o.glb.light = &spot;
    o.glb.medium_json = R"({"scattering": 0.1, "intensity": 7.5})";
    const std::string path = dir.file(compressed ? "c.glb" : "p.glb");
    ASSERT_TRUE(write_mesh(path, m, o).ok());
    const nlohmann::json doc = glb_json(slurp(path));

    // Every buffer view an accessor reads: vertices ARRAY_BUFFER, indices ELEMENT_ARRAY_BUFFER.
    const nlohmann::json& primitive = doc["meshes"][0]["primitives"][0];
    if (!compressed) {
      const auto view_of = [&](int accessor) {
        return doc["bufferViews"][doc["accessors"][accessor]["bufferView"].get<int>()];
      };
      EXPECT_EQ(view_of(primitive["attributes"]["POSITION"])["target"], 34962);
      EXPECT_EQ(view_of(primitive["indices"])["target"], 34963);
    }

    // The light: a spot whose cones are inscribed in (half of fov_y = 30°, the narrower side) and
    // circumscribe (to the corner: atan(√(tan²30° + (1.2 tan 30°)²))) the 1.2:1 frustum.
    ASSERT_EQ(doc["extensionsUsed"].back(), "KHR_lights_punctual");
    const nlohmann::json& light = doc["extensions"]["KHR_lights_punctual"]["lights"][0];
    EXPECT_EQ(light["type"], "spot");
    const double t30 = std::tan(std::numbers::pi / 6);
    EXPECT_NEAR(light["spot"]["innerConeAngle"].get<double>(), std::numbers::pi / 6, 1e-12);
    EXPECT_NEAR(light["spot"]["outerConeAngle"].get<double>(),
                std::atan(std::hypot(t30, 1.2 * t30)), 1e-12);
    EXPECT_EQ(light["intensity"], 7.5);

    // The node at the light's pose, in the default scene: its −Z is the light's direction (−Y),
    // its +Y the light's up (−Z).
    const nlohmann::json& scene_nodes = doc["scenes"][doc.value("scene", 0)]["nodes"];
    const int n = scene_nodes.back().get<int>();
    const nlohmann::json& node = doc["nodes"][n];
    EXPECT_EQ(node["extensions"]["KHR_lights_punctual"]["light"], 0);
    EXPECT_EQ(node["translation"], nlohmann::json({0.0, 4.0, 0.0}));
    const Vec3d forward = rotate(node["rotation"], {0, 0, -1}),
                up = rotate(node["rotation"], {0, 1, 0});
    EXPECT_NEAR(length(forward - Vec3d{0, -1, 0}), 0, 1e-12);
    EXPECT_NEAR(length(up - Vec3d{0, 0, -1}), 0, 1e-12);

    // extras: lightvol reads the light back as the same light; the medium as given.
    const nlohmann::json& extras = node["extras"]["lightvol"];
    Result<Light> back = parse_light(extras["light"].dump(), "extras");
    ASSERT_TRUE(back.ok()) << back.error().message;
    EXPECT_EQ(back->type, spot.type);
    EXPECT_EQ(back->depth, spot.depth);
    EXPECT_EQ(back->view.m, spot.view.m);
    EXPECT_EQ(back->projection.m, spot.projection.m);
    EXPECT_EQ(extras["medium"]["scattering"], 0.1);

    // The mesh reads back as before: the light node adds no geometry.
    Result<Mesh> mesh = read_mesh(path);
    ASSERT_TRUE(mesh.ok()) << mesh.error().message;
    EXPECT_EQ(mesh->num_triangles(), m.num_triangles());
    if (!compressed) {
      EXPECT_EQ(triangle_soup(*mesh), triangle_soup(m));
    }
  }
}

TEST(Export, GlbLightTypes) {
  test::TempDir dir;
  const Mesh m = sample_volume();
  const Light directional = test::light_from_json(test::directional_json());
  const Light omni =
      test::light_from_json(R"({"type": "omni", "position": [1, 2, 3], "near": 0.5, "far": 10})");
  for (const Light* light : {&directional, &omni}) {
    ExportOptions o;
    o.glb.light = light;
    const std::string path = dir.file("l.glb");
    std::filesystem::remove(path);
    ASSERT_TRUE(write_mesh(path, m, o).ok());
    const nlohmann::json doc = glb_json(slurp(path));
    const nlohmann::json& punctual = doc["extensions"]["KHR_lights_punctual"]["lights"][0];
    const nlohmann::json& node = doc["nodes"][doc["nodes"].size() - 1];
    Result<Light> back = parse_light(node["extras"]["lightvol"]["light"].dump(), "extras");
    ASSERT_TRUE(back.ok()) << back.error().message;
    EXPECT_EQ(back->type, light->type);
    EXPECT_FALSE(node["extras"]["lightvol"].contains("medium"));
    EXPECT_EQ(punctual["intensity"], 1.0);
    if (light == &omni) {
      EXPECT_EQ(punctual["type"], "point");
      EXPECT_NEAR(punctual["range"].get<double>(), 10 * std::sqrt(3.0), 1e-12);
      EXPECT_EQ(node["translation"], nlohmann::json({1.0, 2.0, 3.0}));
      EXPECT_FALSE(node.contains("rotation"));
      EXPECT_EQ(back->position.x, 1);
      EXPECT_EQ(back->far, 10);
    } else {
      EXPECT_EQ(punctual["type"], "directional");
      EXPECT_FALSE(punctual.contains("range"));
      EXPECT_NEAR(length(rotate(node["rotation"], {0, 0, -1}) - Vec3d{0, -1, 0}), 0, 1e-12);
      EXPECT_EQ(back->projection.m, directional.projection.m);
    }
  }
}

TEST(Export, LossyEncodingThatBreaksTheVolumeWritesNothing) {
  test::TempDir dir;
  const Mesh m = sample_volume();
  ExportOptions o;
  o.draco_bits = 2;  // 4 levels per axis: faces collapse
  const Status s = write_mesh(dir.file("m.drc"), m, o);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("raise ExportOptions::draco_bits"), std::string::npos)
      << s.error().message;
  o.draco = true;
  EXPECT_FALSE(write_mesh(dir.file("m.glb"), m, o).ok());
  EXPECT_EQ(dir.entries(), 0);
}

TEST(Export, UnknownExtensionIsRejected) {
  test::TempDir dir;
  const Status s = write_mesh(dir.file("m.fbx"), sample_volume());
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("unknown mesh format '.fbx'"), std::string::npos);
  EXPECT_EQ(dir.entries(), 0);
}

}  // namespace
}  // namespace lightvol
