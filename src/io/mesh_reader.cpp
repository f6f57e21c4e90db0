#include <lightvol/io/mesh_reader.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <string_view>
#include <sstream>

#include <OpenMesh/Core/IO/IOManager.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <OpenMesh/Core/System/omstream.hh>
#include <draco/compression/decode.h>
#include <draco/io/gltf_decoder.h>
#include <nlohmann/json.hpp>

#include <lightvol/check/topology.h>
#include <lightvol/export/export.h>
#include <lightvol/io/draco_mesh.h>
#include <lightvol/io/obj_reader.h>
#include <lightvol/io/ply_reader.h>

namespace lightvol {
namespace {

namespace fs = std::filesystem;

// An OpenMesh importer that appends to the flat Mesh: no half-edge structure is built, so a
// multi-million-triangle volume reads in the memory of its two arrays. Faces are fan-triangulated;
// a face naming a vertex that was never added is remembered as the first error.
class FlatImporter final : public OpenMesh::IO::BaseImporter {
 public:
  using VH = OpenMesh::VertexHandle;
  using FH = OpenMesh::FaceHandle;
  using HH = OpenMesh::HalfedgeHandle;
  using EH = OpenMesh::EdgeHandle;
  using Vec3f = OpenMesh::Vec3f;
  using Vec3d = OpenMesh::Vec3d;
  using StatusInfo = OpenMesh::Attributes::StatusInfo;

  // `max_elements` bounds the vertices and faces a file of its size can hold (a truncated file
  // whose header promises billions must not make the readers allocate them).
  FlatImporter(Mesh* mesh, std::size_t max_elements) : mesh_(mesh), max_elements_(max_elements) {}

  std::string error;           // the first bad face, if any
  std::size_t polygons = 0;    // faces as read, before triangulation

  VH add_vertex(const Vec3f& p) override {
    if (mesh_->num_vertices() >= max_elements_) {
      if (error.empty()) error = "more vertices than a file of this size can hold (truncated?)";
      return VH();
    }
    mesh_->positions.insert(mesh_->positions.end(), {p[0], p[1], p[2]});
    return VH(static_cast<int>(mesh_->num_vertices() - 1));
  }
  VH add_vertex(const Vec3d& p) override {
    return add_vertex(Vec3f(static_cast<float>(p[0]), static_cast<float>(p[1]),
                            static_cast<float>(p[2])));
  }
  VH add_vertex() override { return add_vertex(Vec3f(0, 0, 0)); }
  void set_point(VH v, const Vec3f& p) override {
    if (v.idx() < 0 || static_cast<std::size_t>(v.idx()) >= mesh_->num_vertices()) return;
    std::copy(p.data(), p.data() + 3, &mesh_->positions[3 * static_cast<std::size_t>(v.idx())]);
  }

  FH add_face(const VHandles& vs) override {
    const std::size_t face = polygons++;
    if (face >= max_elements_) {
      if (error.empty()) error = "more faces than a file of this size can hold (truncated?)";
      return FH();
    }
    if (vs.size() < 3) {
      if (error.empty())
        error = "face " + std::to_string(face) + " has " + std::to_string(vs.size()) + " vertices";
      return FH();
    }
    // A face's vertex list takes bytes in the file too (fuzz finding, when OpenMesh read PLY: a count of
    // 32,749,287 in a 1 KB file, which OpenMesh filled in and we would have fanned out).
    if (vs.size() > max_elements_) {
      if (error.empty())
        error = "face " + std::to_string(face) + " lists " + std::to_string(vs.size()) +
                " vertices, more than a file of this size can hold (truncated or corrupt)";
      return FH();
    }
    const std::size_t nv = mesh_->num_vertices();
    for (const VH v : vs) {
      if (v.idx() < 0 || static_cast<std::size_t>(v.idx()) >= nv) {
        if (error.empty())
          error = "face " + std::to_string(face) + " names vertex " + std::to_string(v.idx()) +
                  ", but there are " + std::to_string(nv);
        return FH();
      }
    }
    for (std::size_t k = 1; k + 1 < vs.size(); ++k) {
      mesh_->indices.insert(mesh_->indices.end(),
                            {static_cast<std::uint32_t>(vs[0].idx()),
                             static_cast<std::uint32_t>(vs[k].idx()),
                             static_cast<std::uint32_t>(vs[k + 1].idx())});
    }
    return FH(static_cast<int>(mesh_->num_triangles() - 1));
  }
  FH add_face(HH) override { return FH(); }
  HH add_edge(VH, VH) override { return HH(); }

  // Everything else a reader may offer is dropped.
  void add_face_texcoords(FH, VH, const std::vector<OpenMesh::Vec2f>&) override {}
  void add_face_texcoords(FH, VH, const std::vector<Vec3f>&) override {}
  void set_face_texindex(FH, int) override {}
  void set_halfedge(VH, HH) override {}
  void set_normal(VH, const Vec3f&) override {}
  void set_normal(VH, const Vec3d&) override {}
  void set_color(VH, const OpenMesh::Vec3uc&) override {}
  void set_color(VH, const OpenMesh::Vec4uc&) override {}
  void set_color(VH, const Vec3f&) override {}
  void set_color(VH, const OpenMesh::Vec4f&) override {}
  void set_texcoord(VH, const OpenMesh::Vec2f&) override {}
  void set_status(VH, const StatusInfo&) override {}
  void set_next(HH, HH) override {}
  void set_face(HH, FH) override {}
  void request_face_texcoords2D() override {}
  void set_texcoord(HH, const OpenMesh::Vec2f&) override {}
  void set_texcoord(VH, const Vec3f&) override {}
  void set_texcoord(HH, const Vec3f&) override {}
  void set_status(HH, const StatusInfo&) override {}
  void set_color(EH, const OpenMesh::Vec3uc&) override {}
  void set_color(EH, const OpenMesh::Vec4uc&) override {}
  void set_color(EH, const Vec3f&) override {}
  void set_color(EH, const OpenMesh::Vec4f&) override {}
  void set_status(EH, const StatusInfo&) override {}
  void set_normal(FH, const Vec3f&) override {}
  void set_normal(FH, const Vec3d&) override {}
  void set_color(FH, const OpenMesh::Vec3uc&) override {}
  void set_color(FH, const OpenMesh::Vec4uc&) override {}
  void set_color(FH, const Vec3f&) override {}
  void set_color(FH, const OpenMesh::Vec4f&) override {}
  void set_status(FH, const StatusInfo&) override {}
  void add_texture_information(int, std::string) override {}

  bool is_triangle_mesh() const override { return false; }
  void reserve(unsigned int nv, unsigned int, unsigned int nf) override {
    // Headers can lie: reserve only what a sane file of this size could hold.
    constexpr unsigned int kCap = 1u << 26;
    mesh_->positions.reserve(3 * static_cast<std::size_t>(std::min(nv, kCap)));
    mesh_->indices.reserve(3 * static_cast<std::size_t>(std::min(nf, kCap)));
  }
  size_t n_vertices() const override { return mesh_->num_vertices(); }
  size_t n_faces() const override { return polygons; }
  size_t n_edges() const override { return 0; }

 private:
  Mesh* mesh_;
  std::size_t max_elements_;
};

// Every vertex or face takes at least 4 bytes in any of these formats ("0 0 0\n" is 6): more than
// this many elements cannot be in a file of `size` bytes.
std::size_t max_elements(std::uintmax_t size) { return static_cast<std::size_t>(size / 4 + 16); }

// The first `n` bytes of a file (fewer if it is shorter).
std::string file_head(const std::string& path, std::size_t n) {
  std::ifstream in(path, std::ios::binary);
  std::string head(n, '\0');
  in.read(head.data(), static_cast<std::streamsize>(n));
  head.resize(static_cast<std::size_t>(std::max<std::streamsize>(in.gcount(), 0)));
  return head;
}

// Cheap sanity checks before reading: OFF's magic word, and STL's size arithmetic before handing
// the file to OpenMesh, whose reader trusts its input.
Status check_header(const std::string& path, MeshFormat format, std::uintmax_t size) {
  const std::string head = file_head(path, 512);
  switch (format) {
    case MeshFormat::off: {
      const std::size_t at = head.find("OFF");
      if (at == std::string::npos || at > 4)
        return Error{path + ": not an OFF file (no 'OFF' keyword at its start)"};
      return {};  // read_off reads and bounds the rest
    }
    case MeshFormat::stl: {
      if (size >= 84) {
        std::uint32_t n = 0;
        std::memcpy(&n, head.data() + 80, sizeof(n));
        if (size == 84 + 50 * static_cast<std::uintmax_t>(n)) return {};  // binary
      }
      std::size_t first = head.find_first_not_of(" \t\r\n");
      if (first != std::string::npos && head.compare(first, 5, "solid") == 0 &&
          head.find('\0') == std::string::npos)
        return {};  // ASCII
      return Error{path + ": not an STL file (binary size does not match its triangle count, and "
                          "it does not start with 'solid')"};
    }
    default: return {};
  }
}

// Text OFF, read here rather than by OpenMesh, whose reader trusts each face's vertex count: a
// 40-byte file with "500000000 0 1 2" took 12 GB and a minute (fuzz finding). Lines: an optional
// [C][N][ST]OFF keyword (counts may follow it), "V F [E]", V vertex lines (x y z first; normals,
// colours and texture coordinates after them are ignored), F face lines "n i1 .. in" (colours
// after them ignored), fan-triangulated. '#' starts a comment. Binary OFF is refused.
Result<Mesh> read_off(const std::string& path, std::uintmax_t size) {
  if (Status s = check_header(path, MeshFormat::off, size); !s) return s.error();
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{path + ": cannot open: " + std::strerror(errno)};
  std::string line;
  std::size_t number = 0;
  // The next line with content, comments stripped; false at the end of the file.
  const auto next_line = [&](std::istringstream* words) {
    while (std::getline(in, line)) {
      ++number;
      if (const std::size_t hash = line.find('#'); hash != std::string::npos) line.erase(hash);
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
      words->clear();
      words->str(line);
      return true;
    }
    return false;
  };
  const auto at_line = [&] { return path + ": OFF line " + std::to_string(number) + ": "; };
  std::istringstream words;
  if (!next_line(&words)) return Error{path + ": OFF file has no header"};
  std::string keyword;
  words >> keyword;
  if (keyword.size() < 3 || keyword.compare(keyword.size() - 3, 3, "OFF") != 0)
    return Error{at_line() + "expected the OFF keyword, got '" + keyword.substr(0, 40) + "'"};
  if (keyword.find_first_of("4n") != std::string::npos)
    return Error{at_line() + "'" + keyword + "': only 3D OFF is supported"};
  // The counts follow the keyword, on its line or the next.
  std::string rest;
  std::getline(words, rest);
  std::istringstream counts(rest);
  std::string first;
  if (counts >> first && first == "BINARY")
    return Error{at_line() + "binary OFF is not supported; convert it to PLY"};
  counts.clear();
  counts.str(rest);
  long long nv = -1, nf = -1;
  if (first.empty() && !next_line(&counts)) return Error{path + ": OFF file has no vertex and face counts"};
  if (!(counts >> nv >> nf)) return Error{at_line() + "expected the vertex and face counts"};
  const auto most = static_cast<long long>(max_elements(size));
  if (nv < 0 || nf < 0 || nv > most || nf > most || nv + nf > most)
    return Error{path + ": OFF header: " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
                 " faces cannot fit in " + std::to_string(size) + " bytes (truncated file?)"};
  Mesh mesh;
  mesh.positions.reserve(3 * static_cast<std::size_t>(nv));
  for (long long v = 0; v < nv; ++v) {
    if (!next_line(&words))
      return Error{path + ": OFF file ends after " + std::to_string(v) + " of " + std::to_string(nv) + " vertices"};
    double x = 0, y = 0, z = 0;
    if (!(words >> x >> y >> z)) return Error{at_line() + "expected a vertex: x y z"};
    mesh.positions.insert(mesh.positions.end(), {static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)});
  }
  std::vector<long long> face;
  for (long long f = 0; f < nf; ++f) {
    if (!next_line(&words))
      return Error{path + ": OFF file ends after " + std::to_string(f) + " of " + std::to_string(nf) + " faces"};
    long long n = 0;
    if (!(words >> n) || n < 3 || n > static_cast<long long>(line.size()))
      return Error{at_line() + "expected a face: a vertex count of at least 3, then that many vertices"};
    face.resize(static_cast<std::size_t>(n));
    for (long long& i : face) {
      if (!(words >> i)) return Error{at_line() + "face " + std::to_string(f) + " lists fewer than " + std::to_string(n) + " vertices"};
      if (i < 0 || i >= nv)
        return Error{at_line() + "face " + std::to_string(f) + " names vertex " + std::to_string(i) + ", but there are " + std::to_string(nv)};
    }
    for (std::size_t k = 1; k + 1 < face.size(); ++k)
      mesh.indices.insert(mesh.indices.end(), {static_cast<std::uint32_t>(face[0]), static_cast<std::uint32_t>(face[k]), static_cast<std::uint32_t>(face[k + 1])});
  }
  return mesh;
}

Result<Mesh> read_with_openmesh(const std::string& path, MeshFormat format, std::uintmax_t size) {
  if (Status s = check_header(path, format, size); !s) return s.error();
  // OpenMesh chats (and complains) on its log streams; the Error says what went wrong instead.
  omlog().disable();
  omout().disable();
  omerr().disable();
  Mesh mesh;
  FlatImporter importer(&mesh, max_elements(size));
  OpenMesh::IO::Options options;
  bool read = false;
  try {
    read = OpenMesh::IO::IOManager().read(path, importer, options);
  } catch (const std::exception& e) {
    return Error{path + ": cannot read: " + e.what()};
  }
  if (!importer.error.empty()) return Error{path + ": " + importer.error};
  if (!read) return Error{path + ": cannot read: malformed or truncated file"};
  return mesh;
}

// Draco's glTF decoder (tinygltf underneath) trusts the file: an index past the end of an
// attribute made it copy out of bounds, a view past its buffer made it read freed memory (fuzz
// findings), and it reads any file an image's or a buffer's 'uri' names. So a GLB is checked
// first, and Draco gets a rebuilt one holding only what a mesh's positions need. Checked: the
// container's chunks fit the file; every reference names an existing object; the nodes form
// trees; every accessor lies inside its buffer view, inside buffer 0 (the BIN chunk); every
// index is below its primitive's POSITION count. Rebuilt without: materials, textures, images,
// samplers, skins, animations, cameras, morph targets, attributes other than POSITION, 'uri's,
// extensions other than KHR_draco_mesh_compression (whose primitives Draco's own decoder
// checks). Returns the rebuilt GLB, or the first problem.
Result<std::string> sanitize_glb(const std::string& bytes, const std::string& path) {
  const auto u32 = [&](std::size_t at) {
    std::uint32_t v = 0;
    std::memcpy(&v, bytes.data() + at, 4);
    return v;
  };
  const auto fail = [&](const std::string& what) { return Error{path + ": glTF binary: " + what}; };
  if (bytes.size() < 20) return fail("shorter than its header");
  if (u32(4) != 2) return fail("version " + std::to_string(u32(4)) + ", not 2");
  if (u32(8) > bytes.size()) return fail("header claims " + std::to_string(u32(8)) + " bytes, the file has " + std::to_string(bytes.size()));
  const std::size_t json_length = u32(12);
  if (u32(16) != 0x4E4F534Au || json_length > bytes.size() - 20) return fail("the first chunk is not a whole JSON chunk");
  std::string_view bin;
  const std::size_t bin_at = 20 + ((json_length + 3) & ~std::size_t{3});
  if (bin_at + 8 <= bytes.size() && u32(bin_at + 4) == 0x004E4942u) {
    const std::size_t bin_length = u32(bin_at);
    if (bin_length > bytes.size() - bin_at - 8) return fail("the BIN chunk runs past the end of the file");
    bin = std::string_view(bytes).substr(bin_at + 8, bin_length);
  }
  const nlohmann::json doc = nlohmann::json::parse(bytes.begin() + 20, bytes.begin() + 20 + static_cast<std::ptrdiff_t>(json_length), nullptr, false);
  if (doc.is_discarded() || !doc.is_object()) return fail("the JSON chunk is not a JSON object");

  // Checked lookups: a missing or mistyped member reads as `fallback`.
  const auto member = [](const nlohmann::json& j, const char* key) -> const nlohmann::json* {
    if (!j.is_object()) return nullptr;
    const auto it = j.find(key);
    return it == j.end() ? nullptr : &*it;
  };
  const auto integer = [&](const nlohmann::json& j, const char* key, std::int64_t fallback) {
    const nlohmann::json* m = member(j, key);
    return m && m->is_number_integer() ? m->get<std::int64_t>() : fallback;
  };
  const auto element = [&](const char* array, std::int64_t index) -> const nlohmann::json* {
    const nlohmann::json* a = member(doc, array);
    if (!a || !a->is_array() || index < 0 || index >= static_cast<std::int64_t>(a->size())) return nullptr;
    return &(*a)[static_cast<std::size_t>(index)];
  };
  static const std::map<std::string, int> kComponents = {{"SCALAR", 1}, {"VEC2", 2}, {"VEC3", 3}, {"VEC4", 4}, {"MAT2", 4}, {"MAT3", 9}, {"MAT4", 16}};
  const auto component_size = [](std::int64_t type) -> int {
    switch (type) {
      case 5120: case 5121: return 1;
      case 5122: case 5123: return 2;
      case 5125: case 5126: return 4;
      default: return 0;
    }
  };
  // The bytes of accessor `index` as (data, stride, element size, count), or an error.
  struct View {
    const char* data = nullptr;
    std::size_t stride = 0, element = 0, count = 0;
    std::int64_t component_type = 0;
  };
  const auto accessor_view = [&](std::int64_t index, View* view) -> Status {
    const std::string name = "accessor " + std::to_string(index);
    const nlohmann::json* accessor = element("accessors", index);
    if (!accessor) return fail(name + " does not exist");
    if (member(*accessor, "sparse")) return fail(name + " is sparse (not supported)");
    const nlohmann::json* type = member(*accessor, "type");
    const auto components = type && type->is_string() ? kComponents.find(type->get<std::string>()) : kComponents.end();
    view->component_type = integer(*accessor, "componentType", 0);
    const int size = component_size(view->component_type);
    if (components == kComponents.end() || size == 0) return fail(name + " has an unknown type");
    const std::int64_t count = integer(*accessor, "count", -1);
    if (count < 1) return fail(name + " has no valid count");
    const nlohmann::json* buffer_view = element("bufferViews", integer(*accessor, "bufferView", -1));
    if (!buffer_view) return fail(name + " has no buffer view");
    if (integer(*buffer_view, "buffer", -1) != 0) return fail(name + " is not in the GLB's BIN chunk");
    const std::int64_t view_offset = integer(*buffer_view, "byteOffset", 0), view_length = integer(*buffer_view, "byteLength", -1);
    if (view_offset < 0 || view_length < 0 || view_offset > static_cast<std::int64_t>(bin.size()) ||
        view_length > static_cast<std::int64_t>(bin.size()) - view_offset)
      return fail(name + ": its buffer view lies outside buffer 0");
    const std::int64_t element_size = components->second * size;
    const std::int64_t stride = integer(*buffer_view, "byteStride", element_size);
    const std::int64_t offset = integer(*accessor, "byteOffset", 0);
    if (stride < element_size || stride > 252 || offset < 0 || count > view_length ||
        offset + (count - 1) * stride + element_size > view_length)
      return fail(name + " runs past the end of its buffer view");
    view->data = bin.data() + view_offset + offset;
    view->stride = static_cast<std::size_t>(stride);
    view->element = static_cast<std::size_t>(element_size);
    view->count = static_cast<std::size_t>(count);
    return {};
  };

  // Every reference between objects must name an existing one (Draco follows them unchecked: a
  // node naming mesh 5 of 1 crashed it), and the nodes must form trees (its traversal recurses).
  const auto array_size = [&](const char* array) -> std::int64_t {
    const nlohmann::json* a = member(doc, array);
    return a && a->is_array() ? static_cast<std::int64_t>(a->size()) : 0;
  };
  const auto reference = [&](const nlohmann::json& object, const char* key, const char* array,
                             const std::string& where) -> Status {
    const nlohmann::json* m = member(object, key);
    if (!m) return {};
    if (!m->is_number_integer() || m->get<std::int64_t>() < 0 ||
        m->get<std::int64_t>() >= array_size(array))
      return fail(where + ": '" + key + "' names no element of '" + array + "'");
    return {};
  };
  const auto each = [&](const char* array, const auto& visit) -> Status {
    const nlohmann::json* a = member(doc, array);
    if (!a) return {};
    if (!a->is_array()) return fail("'" + std::string(array) + "' is not an array");
    for (std::size_t i = 0; i < a->size(); ++i)
      if (Status s = visit((*a)[i], static_cast<std::int64_t>(i), std::string(array) + " " + std::to_string(i)); !s)
        return s;
    return {};
  };
  const auto references = [&](const nlohmann::json& object, const char* key, const char* array,
                              const std::string& where) -> Status {
    const nlohmann::json* list = member(object, key);
    if (!list) return {};
    if (!list->is_array()) return fail(where + ": '" + key + "' is not an array");
    for (const nlohmann::json& item : *list)
      if (!item.is_number_integer() || item.get<std::int64_t>() < 0 ||
          item.get<std::int64_t>() >= array_size(array))
        return fail(where + ": '" + key + "' names no element of '" + array + "'");
    return {};
  };
  if (Status s = reference(doc, "scene", "scenes", "the document"); !s) return s.error();
  if (Status s = each("scenes", [&](const nlohmann::json& o, std::int64_t, const std::string& w) { return references(o, "nodes", "nodes", w); }); !s) return s.error();
  std::vector<std::int64_t> parent(static_cast<std::size_t>(array_size("nodes")), -1);
  if (Status s = each("nodes", [&](const nlohmann::json& o, std::int64_t self, const std::string& w) -> Status {
        for (const char* key : {"mesh", "skin", "camera"}) {
          const char* array = std::strcmp(key, "mesh") == 0 ? "meshes" : std::strcmp(key, "skin") == 0 ? "skins" : "cameras";
          if (Status r = reference(o, key, array, w); !r) return r;
        }
        if (Status r = references(o, "children", "nodes", w); !r) return r;
        if (const nlohmann::json* children = member(o, "children")) {
          for (const nlohmann::json& c : *children) {
            std::int64_t& p = parent[static_cast<std::size_t>(c.get<std::int64_t>())];
            if (p != -1 || c.get<std::int64_t>() == self) return fail(w + ": the nodes do not form trees");
            p = self;
          }
        }
        return {};
      }); !s) return s.error();
  for (std::size_t n = 0; n < parent.size(); ++n) {  // no cycles: every chain of parents ends
    std::int64_t at = static_cast<std::int64_t>(n);
    for (std::size_t steps = 0; at != -1; ++steps, at = parent[static_cast<std::size_t>(at)])
      if (steps > parent.size()) return fail("node " + std::to_string(n) + " is its own ancestor");
  }
  if (Status s = each("meshes", [&](const nlohmann::json& mesh, std::int64_t, const std::string& w) -> Status {
        const nlohmann::json* primitives = member(mesh, "primitives");
        if (!primitives || !primitives->is_array()) return fail(w + " has no primitives");
        return {};
      }); !s) return s.error();
  if (array_size("bufferViews") > 0) {
    const nlohmann::json* buffers = member(doc, "buffers");
    if (!buffers || !buffers->is_array() || buffers->size() != 1)
      return fail("expected exactly one buffer, the BIN chunk");
    const std::int64_t length = integer((*buffers)[0], "byteLength", -1);
    if (length < 0 || length > static_cast<std::int64_t>(bin.size()))
      return fail("buffer 0 is longer than the BIN chunk");
    // Draco keeps the buffer's byteLength bytes of the chunk: views are checked against those
    // (fuzz finding: a view inside the chunk but past the buffer made it read freed memory).
    bin = bin.substr(0, static_cast<std::size_t>(length));
  }
  if (Status s = each("bufferViews", [&](const nlohmann::json& view, std::int64_t, const std::string& w) -> Status {
        const std::int64_t offset = integer(view, "byteOffset", 0), length = integer(view, "byteLength", -1);
        if (integer(view, "buffer", -1) != 0 || offset < 0 || length < 0 ||
            offset > static_cast<std::int64_t>(bin.size()) || length > static_cast<std::int64_t>(bin.size()) - offset)
          return fail(w + " lies outside buffer 0");
        return {};
      }); !s) return s.error();
  if (Status s = each("accessors", [&](const nlohmann::json& accessor, std::int64_t index, const std::string&) -> Status {
        if (!member(accessor, "bufferView")) return {};  // Draco-compressed data, or unused
        View view;
        return accessor_view(index, &view);
      }); !s) return s.error();

  // What Draco gets: the document's geometry and nothing else.
  nlohmann::json clean = {{"asset", {{"version", "2.0"}}}};
  for (const char* key : {"scene", "accessors", "bufferViews"})
    if (const nlohmann::json* m = member(doc, key)) clean[key] = *m;
  if (array_size("bufferViews") > 0) clean["buffers"] = nlohmann::json::array({{{"byteLength", bin.size()}}});
  if (Status s = each("scenes", [&](const nlohmann::json& o, std::int64_t, const std::string&) -> Status {
        nlohmann::json scene = nlohmann::json::object();
        if (const nlohmann::json* nodes = member(o, "nodes")) scene["nodes"] = *nodes;
        clean["scenes"].push_back(scene);
        return {};
      }); !s) return s.error();
  if (Status s = each("nodes", [&](const nlohmann::json& o, std::int64_t, const std::string&) -> Status {
        nlohmann::json node = nlohmann::json::object();
        for (const char* key : {"mesh", "children", "matrix", "translation", "rotation", "scale"})
          if (const nlohmann::json* m = member(o, key)) node[key] = *m;
        clean["nodes"].push_back(node);
        return {};
      }); !s) return s.error();
  constexpr const char* kDraco = "KHR_draco_mesh_compression";
  if (Status s = each("meshes", [&](const nlohmann::json& mesh, std::int64_t m, const std::string&) -> Status {
        nlohmann::json kept = {{"primitives", nlohmann::json::array()}};
        const nlohmann::json& primitives = *member(mesh, "primitives");
        for (std::size_t p = 0; p < primitives.size(); ++p) {
          const nlohmann::json& primitive = primitives[p];
          const std::string where = "mesh " + std::to_string(m) + " primitive " + std::to_string(p);
          nlohmann::json out = nlohmann::json::object();
          if (const nlohmann::json* mode = member(primitive, "mode")) out["mode"] = *mode;
          const nlohmann::json* extensions = member(primitive, "extensions");
          const nlohmann::json* attributes = member(primitive, "attributes");
          if (!attributes || !attributes->is_object()) return fail(where + " has no attributes");
          if (extensions && member(*extensions, kDraco)) {  // Draco's decoder checks its data
            // ... but not the references around it (fuzz finding: 'indices' naming accessor 77
            // of 2 crashed it).
            const nlohmann::json& draco = *member(*extensions, kDraco);
            if (Status r = reference(primitive, "indices", "accessors", where); !r) return r;
            if (Status r = reference(draco, "bufferView", "bufferViews", where + " " + kDraco); !r) return r;
            const nlohmann::json* ids = member(draco, "attributes");
            if (!member(draco, "bufferView") || !ids || !ids->is_object())
              return fail(where + ": " + kDraco + " needs a bufferView and attributes");
            // POSITION alone is kept: its accessor must be float VEC3, and its id must name a
            // 3-component attribute of the compressed data, which is decoded here to see (a
            // missing id crashed Draco's glTF decoder).
            const nlohmann::json* id = member(*ids, "POSITION");
            const nlohmann::json* position = member(*attributes, "POSITION");
            if (!id || !id->is_number_integer() || !position || !position->is_number_integer())
              return fail(where + ": " + kDraco + " has no POSITION");
            if (Status r = reference(*attributes, "POSITION", "accessors", where); !r) return r;
            const nlohmann::json& accessor = (*member(doc, "accessors"))[position->get<std::size_t>()];
            const nlohmann::json* type = member(accessor, "type");
            if (integer(accessor, "componentType", 0) != 5126 || !type || *type != "VEC3")
              return fail(where + ": POSITION is not a float VEC3 accessor");
            const nlohmann::json& view = (*member(doc, "bufferViews"))[static_cast<std::size_t>(integer(draco, "bufferView", 0))];
            draco::DecoderBuffer compressed;
            compressed.Init(bin.data() + integer(view, "byteOffset", 0), static_cast<std::size_t>(integer(view, "byteLength", 0)));
            draco::Decoder decoder;
            auto decoded = decoder.DecodeMeshFromBuffer(&compressed);
            if (!decoded.ok()) return fail(where + ": its Draco data does not decode: " + decoded.status().error_msg_string());
            const draco::PointAttribute* attribute =
                id->get<std::int64_t>() < 0 || id->get<std::int64_t>() > std::numeric_limits<std::int32_t>::max()
                    ? nullptr
                    : decoded.value()->GetAttributeByUniqueId(static_cast<std::uint32_t>(id->get<std::int64_t>()));
            if (!attribute || attribute->num_components() != 3)
              return fail(where + ": " + kDraco + " POSITION names no 3-component attribute of its data");
            out["extensions"] = {{kDraco, {{"bufferView", draco["bufferView"]}, {"attributes", {{"POSITION", *id}}}}}};
            out["attributes"] = {{"POSITION", *position}};
            if (const nlohmann::json* indices = member(primitive, "indices")) out["indices"] = *indices;
            kept["primitives"].push_back(out);
            continue;
          }
          const nlohmann::json* position = member(*attributes, "POSITION");
          if (!position || !position->is_number_integer()) return fail(where + " has no POSITION accessor");
          View positions;
          if (Status r = accessor_view(position->get<std::int64_t>(), &positions); !r) return r;
          out["attributes"] = {{"POSITION", *position}};
          if (const nlohmann::json* indices = member(primitive, "indices")) {
            View view;
            if (!indices->is_number_integer()) return fail(where + ": indices is not an accessor index");
            if (Status r = accessor_view(indices->get<std::int64_t>(), &view); !r) return r;
            const int size = component_size(view.component_type);
            if (view.element != static_cast<std::size_t>(size) || view.component_type == 5120 ||
                view.component_type == 5122 || view.component_type == 5126)
              return fail(where + ": indices are not unsigned integer scalars");
            for (std::size_t i = 0; i < view.count; ++i) {
              const char* at = view.data + i * view.stride;
              std::uint32_t value = 0;
              if (size == 1) value = static_cast<std::uint8_t>(*at);
              if (size == 2) { std::uint16_t v16; std::memcpy(&v16, at, 2); value = v16; }
              if (size == 4) std::memcpy(&value, at, 4);
              if (value >= positions.count)
                return fail(where + ": index " + std::to_string(i) + " is " + std::to_string(value) +
                            ", but its attributes have " + std::to_string(positions.count) + " elements");
            }
            out["indices"] = *indices;
          }
          kept["primitives"].push_back(out);
        }
        clean["meshes"].push_back(kept);
        return {};
      }); !s) return s.error();
  for (const char* key : {"extensionsUsed", "extensionsRequired"}) {
    const nlohmann::json* list = member(doc, key);
    if (list && list->is_array() && std::find(list->begin(), list->end(), kDraco) != list->end())
      clean[key] = nlohmann::json::array({kDraco});
  }

  // The rebuilt container: JSON padded with spaces, BIN with zeros, to 4 bytes.
  std::string json = clean.dump();
  json.resize((json.size() + 3) & ~std::size_t{3}, ' ');
  std::string glb;
  const auto put = [&](std::uint32_t v) { glb.append(reinterpret_cast<const char*>(&v), 4); };
  const std::size_t bin_padded = (bin.size() + 3) & ~std::size_t{3};
  const std::size_t total = 12 + 8 + json.size() + (bin.empty() ? 0 : 8 + bin_padded);
  if (total > std::numeric_limits<std::uint32_t>::max()) return fail("larger than 4 GiB");
  glb.append("glTF");
  put(2);
  put(static_cast<std::uint32_t>(total));
  put(static_cast<std::uint32_t>(json.size()));
  put(0x4E4F534Au);
  glb += json;
  if (!bin.empty()) {
    put(static_cast<std::uint32_t>(bin_padded));
    put(0x004E4942u);
    glb.append(bin);
    glb.resize(total, '\0');
  }
  return glb;
}

// A third-party message on one line: runs of line breaks become "; ".
std::string one_line(const std::string& message) {
  std::string out;
  bool broken = false;
  for (const char c : message) {
    if (c == '\n' || c == '\r') {
      broken = !out.empty();
      continue;
    }
    if (broken) out += "; ";
    broken = false;
    out += c;
  }
  return out;
}

Result<Mesh> read_with_draco(const std::string& path, MeshFormat format) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) return Error{path + ": cannot read: " + std::strerror(errno)};
  draco::DecoderBuffer buffer;
  buffer.Init(bytes.data(), bytes.size());
  std::unique_ptr<draco::Mesh> decoded;
  if (format == MeshFormat::drc) {
    draco::Decoder decoder;
    auto result = decoder.DecodeMeshFromBuffer(&buffer);
    if (!result.ok())
      return Error{path + ": not a Draco mesh: " + one_line(result.status().error_msg_string())};
    decoded = std::move(result).value();
  } else {
    if (bytes.size() < 12 || bytes.compare(0, 4, "glTF") != 0)
      return Error{path + ": not a GLB file (no 'glTF' magic)"};
    const Result<std::string> clean = sanitize_glb(bytes, path);
    if (!clean) return clean.error();
    draco::DecoderBuffer rebuilt;
    rebuilt.Init(clean->data(), clean->size());
    draco::GltfDecoder decoder;
    auto result = decoder.DecodeFromBuffer(&rebuilt);
    if (!result.ok())
      return Error{path + ": cannot decode glTF: " + one_line(result.status().error_msg_string())};
    decoded = std::move(result).value();
  }
  if (!decoded->GetNamedAttribute(draco::GeometryAttribute::POSITION))
    return Error{path + ": the mesh has no POSITION attribute"};
  Result<Mesh> mesh = detail::from_draco(*decoded);
  if (!mesh) return Error{path + ": " + mesh.error().message};
  return mesh;
}

}  // namespace

Result<Mesh> read_mesh(const std::string& path) {
  const Result<MeshFormat> format = mesh_format_from_path(path);
  if (!format) return format.error();
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st)) return Error{path + ": no such file"};
  if (!fs::is_regular_file(st)) return Error{path + ": not a regular file"};
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) return Error{path + ": cannot read: " + ec.message()};
  if (size == 0) return Error{path + ": empty file"};
  if (std::ifstream probe(path, std::ios::binary); !probe)
    return Error{path + ": cannot open: " + std::strerror(errno)};

  Result<Mesh> mesh = (*format == MeshFormat::drc || *format == MeshFormat::glb)
                          ? read_with_draco(path, *format)
                          : *format == MeshFormat::off ? read_off(path, size)
                          : *format == MeshFormat::ply ? detail::read_ply(path, size)
                          : *format == MeshFormat::obj ? detail::read_obj(path)
                                                       : read_with_openmesh(path, *format, size);
  if (!mesh) return mesh;
  if (mesh->num_triangles() == 0) return Error{path + ": has no triangles"};
  if (mesh->num_vertices() >= std::numeric_limits<std::uint32_t>::max())
    return Error{path + ": has too many vertices"};
  for (const float x : mesh->positions) {
    if (!std::isfinite(x)) return Error{path + ": has a vertex with a non-finite coordinate"};
  }
  return weld_identical_positions(*mesh);
}

}  // namespace lightvol
