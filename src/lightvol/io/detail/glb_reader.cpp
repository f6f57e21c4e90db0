#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <lightvol/core/check.h>
#include <lightvol/core/limits.h>
#include <lightvol/io/detail/glb_reader.h>

namespace lightvol::detail {
namespace {

using Json = nlohmann::json;
constexpr const char* kDraco = "KHR_draco_mesh_compression";
constexpr std::uint32_t kJsonChunk = 0x4E4F534Au, kBinChunk = 0x004E4942u;

// Checked lookups: a missing member, or a non-object, gives nullptr.
const Json* member(const Json& j, const char* key) {
  if (!j.is_object()) return nullptr;
  const auto it = j.find(key);
  return it == j.end() ? nullptr : &*it;
}

// An integer member, or `fallback` when it is missing or not an integer.
std::int64_t integer(const Json& j, const char* key, std::int64_t fallback) {
  const Json* m = member(j, key);
  return m && m->is_number_integer() ? m->get<std::int64_t>() : fallback;
}

int component_size(std::int64_t type) {
  switch (type) {
    case 5120:
    case 5121:
      return 1;  // (unsigned) byte
    case 5122:
    case 5123:
      return 2;  // (unsigned) short
    case 5125:
    case 5126:
      return 4;  // unsigned int, float
    default:
      return 0;
  }
}

// An accessor's bytes: `count` elements of `element` bytes, `stride` apart.
struct Accessor {
  const char* data = nullptr;
  std::size_t stride = 0, element = 0, count = 0;
  std::int64_t component_type = 0;
  int components = 0;
};

class GlbReader {
 public:
  GlbReader(std::string_view bytes, const std::string& path) : bytes_(bytes), path_(path) {}

  Result<DracoMesh> read() {
    if (Status s = parse_container(); !s) return s.error();
    if (Status s = check_references(); !s) return s.error();
    cache_.resize(static_cast<std::size_t>(array_size("meshes")));
    const Json* scenes = member(doc_, "scenes");
    if (!scenes || scenes->empty()) {  // no scene: every mesh once, where it stands
      for (std::int64_t m = 0; m < array_size("meshes"); ++m)
        instances_.push_back({m, Eigen::Matrix4d::Identity()});
    } else if (Status s = traverse(integer(doc_, "scene", 0)); !s) {
      return s.error();
    }
    decode_draco_primitives();
    if (Status s = check_size(); !s) return s.error();
    for (const Instance& instance : instances_)
      emit(*cache_[static_cast<std::size_t>(instance.mesh)], instance.transform);
    return std::move(out_);
  }

 private:
  Error fail(const std::string& what) const { return Error{path_ + ": glTF binary: " + what}; }

  std::int64_t array_size(const char* array) const {
    const Json* a = member(doc_, array);
    return a && a->is_array() ? static_cast<std::int64_t>(a->size()) : 0;
  }
  const Json& at(const char* array, std::int64_t index) const {
    return (*member(doc_, array))[static_cast<std::size_t>(index)];
  }

  // The 12-byte header, the JSON chunk and the optional BIN chunk, each within the file.
  Status parse_container() {
    const auto u32 = [&](std::size_t at) {
      std::uint32_t v = 0;
      std::memcpy(&v, bytes_.data() + at, 4);
      return v;
    };
    if (bytes_.size() < 20) return fail("shorter than its header");
    if (u32(4) != 2) return fail("version " + std::to_string(u32(4)) + ", not 2");
    // Its length is the file's (glTF 2.0, "Binary glTF Layout"): fewer bytes are a truncated file,
    // more are bytes after its last chunk, which are not silently dropped.
    if (u32(8) != bytes_.size())
      return fail("header claims " + std::to_string(u32(8)) + " bytes, the file has " +
                  std::to_string(bytes_.size()));
    const std::size_t json_length = u32(12);
    if (u32(16) != kJsonChunk || json_length > bytes_.size() - 20)
      return fail("the first chunk is not a whole JSON chunk");
    const std::size_t bin_at = 20 + ((json_length + 3) & ~std::size_t{3});
    if (bin_at + 8 <= bytes_.size() && u32(bin_at + 4) == kBinChunk) {
      const std::size_t bin_length = u32(bin_at);
      if (bin_length > bytes_.size() - bin_at - 8)
        return fail("the BIN chunk runs past the end of the file");
      bin_ = bytes_.substr(bin_at + 8, bin_length);
    }
    doc_ =
        Json::parse(bytes_.begin() + 20,
                    bytes_.begin() + 20 + static_cast<std::ptrdiff_t>(json_length), nullptr, false);
    if (doc_.is_discarded() || !doc_.is_object())
      return fail("the JSON chunk is not a JSON object");
    return {};
  }

  // `object[key]`, when present, must name an element of the top-level `array`.
  Status reference(const Json& object, const char* key, const char* array,
                   const std::string& where) const {
    const Json* m = member(object, key);
    if (!m) return {};
    if (!m->is_number_integer() || m->get<std::int64_t>() < 0 ||
        m->get<std::int64_t>() >= array_size(array))
      return fail(where + ": '" + key + "' names no element of '" + array + "'");
    return {};
  }
  // `object[key]`, when present, must be an array of such references.
  Status references(const Json& object, const char* key, const char* array,
                    const std::string& where) const {
    const Json* list = member(object, key);
    if (!list) return {};
    if (!list->is_array()) return fail(where + ": '" + key + "' is not an array");
    for (const Json& item : *list)
      if (!item.is_number_integer() || item.get<std::int64_t>() < 0 ||
          item.get<std::int64_t>() >= array_size(array))
        return fail(where + ": '" + key + "' names no element of '" + array + "'");
    return {};
  }
  // Calls visit(element, index, "array index") on each element of a top-level array.
  template <typename Visit>
  Status each(const char* array, const Visit& visit) const {
    const Json* a = member(doc_, array);
    if (!a) return {};
    if (!a->is_array()) return fail("'" + std::string(array) + "' is not an array");
    for (std::size_t i = 0; i < a->size(); ++i)
      if (Status s = visit((*a)[i], static_cast<std::int64_t>(i),
                           std::string(array) + " " + std::to_string(i));
          !s)
        return s;
    return {};
  }

  // The document's structure, before anything is followed: scenes name nodes, nodes name meshes
  // and nodes, meshes have primitives, and buffer views lie inside buffer 0, the BIN chunk.
  Status check_references() {
    if (Status s = reference(doc_, "scene", "scenes", "the document"); !s) return s;
    if (Status s = each("scenes",
                        [&](const Json& o, std::int64_t, const std::string& w) {
                          return references(o, "nodes", "nodes", w);
                        });
        !s)
      return s;
    if (Status s = each("nodes",
                        [&](const Json& o, std::int64_t, const std::string& w) -> Status {
                          if (Status r = reference(o, "mesh", "meshes", w); !r) return r;
                          return references(o, "children", "nodes", w);
                        });
        !s)
      return s;
    if (Status s = each("meshes",
                        [&](const Json& mesh, std::int64_t, const std::string& w) -> Status {
                          const Json* primitives = member(mesh, "primitives");
                          if (!primitives || !primitives->is_array())
                            return fail(w + " has no primitives");
                          return {};
                        });
        !s)
      return s;
    if (array_size("bufferViews") > 0) {
      const Json* buffers = member(doc_, "buffers");
      if (!buffers || !buffers->is_array() || buffers->size() != 1)
        return fail("expected exactly one buffer, the BIN chunk");
      const std::int64_t length = integer((*buffers)[0], "byteLength", -1);
      if (length < 0 || length > static_cast<std::int64_t>(bin_.size()))
        return fail("buffer 0 is longer than the BIN chunk");
      bin_ = bin_.substr(0, static_cast<std::size_t>(length));
    }
    return each("bufferViews", [&](const Json& view, std::int64_t, const std::string& w) -> Status {
      const std::int64_t offset = integer(view, "byteOffset", 0),
                         length = integer(view, "byteLength", -1);
      if (integer(view, "buffer", -1) != 0 || offset < 0 || length < 0 ||
          offset > static_cast<std::int64_t>(bin_.size()) ||
          length > static_cast<std::int64_t>(bin_.size()) - offset)
        return fail(w + " lies outside buffer 0");
      return {};
    });
  }

  // The bytes of buffer view `index` (checked to lie inside buffer 0 already).
  std::string_view view_bytes(std::int64_t index) const {
    const Json& view = at("bufferViews", index);
    return bin_.substr(static_cast<std::size_t>(integer(view, "byteOffset", 0)),
                       static_cast<std::size_t>(integer(view, "byteLength", 0)));
  }

  Result<Accessor> accessor(std::int64_t index) const {
    static const std::map<std::string, int> kComponents = {{"SCALAR", 1}, {"VEC2", 2}, {"VEC3", 3},
                                                           {"VEC4", 4},   {"MAT2", 4}, {"MAT3", 9},
                                                           {"MAT4", 16}};
    const std::string name = "accessor " + std::to_string(index);
    if (index < 0 || index >= array_size("accessors")) return fail(name + " does not exist");
    const Json& json = at("accessors", index);
    if (member(json, "sparse")) return fail(name + " is sparse (not supported)");
    const Json* type = member(json, "type");
    const auto components =
        type && type->is_string() ? kComponents.find(type->get<std::string>()) : kComponents.end();
    Accessor a;
    a.component_type = integer(json, "componentType", 0);
    const int size = component_size(a.component_type);
    if (components == kComponents.end() || size == 0) return fail(name + " has an unknown type");
    a.components = components->second;
    const std::int64_t count = integer(json, "count", -1);
    if (count < 1) return fail(name + " has no valid count");
    const std::int64_t view_index = integer(json, "bufferView", -1);
    if (view_index < 0 || view_index >= array_size("bufferViews"))
      return fail(name + " has no buffer view");
    const std::string_view view = view_bytes(view_index);
    const std::int64_t element = a.components * size;
    const std::int64_t stride = integer(at("bufferViews", view_index), "byteStride", element);
    const std::int64_t offset = integer(json, "byteOffset", 0),
                       length = static_cast<std::int64_t>(view.size());
    if (stride < element || stride > 252 || offset < 0 || count > length ||
        offset + (count - 1) * stride + element > length)
      return fail(name + " runs past the end of its buffer view");
    a.data = view.data() + offset;
    a.stride = static_cast<std::size_t>(stride);
    a.element = static_cast<std::size_t>(element);
    a.count = static_cast<std::size_t>(count);
    return a;
  }

  // POSITION: its accessor index, which must name a float VEC3 accessor.
  Result<std::int64_t> position_accessor(const Json& attributes, const std::string& where) const {
    const Json* position = member(attributes, "POSITION");
    if (!position || !position->is_number_integer())
      return fail(where + " has no POSITION accessor");
    if (Status s = reference(attributes, "POSITION", "accessors", where); !s) return s.error();
    const Json& json = at("accessors", position->get<std::int64_t>());
    const Json* type = member(json, "type");
    if (integer(json, "componentType", 0) != 5126 || !type || *type != "VEC3")
      return fail(where + ": POSITION is not a float VEC3 accessor");
    return position->get<std::int64_t>();
  }

  // A KHR_draco_mesh_compression primitive's data: its buffer view and POSITION's unique id there.
  using DracoKey = std::pair<std::int64_t, std::uint32_t>;
  Result<DracoKey> draco_key(const Json& primitive, const Json& draco,
                             const std::string& where) const {
    // Its data is Draco's to check, the references around it are ours ('indices' naming accessor
    // 77 of 2 crashed Draco's glTF decoder, whose fuzzing led to this reader).
    if (Status s = reference(primitive, "indices", "accessors", where); !s) return s.error();
    if (Status s = reference(draco, "bufferView", "bufferViews", where + " " + kDraco); !s)
      return s.error();
    const Json* ids = member(draco, "attributes");
    if (!member(draco, "bufferView") || !ids || !ids->is_object())
      return fail(where + ": " + kDraco + " needs a bufferView and attributes");
    const Json* id = member(*ids, "POSITION");
    if (!id || !id->is_number_integer()) return fail(where + ": " + kDraco + " has no POSITION");
    if (Result<std::int64_t> p = position_accessor(*member(primitive, "attributes"), where); !p)
      return p.error();
    const std::int64_t unique_id = id->get<std::int64_t>();
    if (unique_id < 0 || unique_id > std::numeric_limits<std::int32_t>::max())
      return fail(where + ": " + kDraco + " POSITION names no 3-component attribute of its data");
    return DracoKey{integer(draco, "bufferView", 0), static_cast<std::uint32_t>(unique_id)};
  }

  // The Draco extension of a primitive, or nullptr.
  static const Json* draco_extension(const Json& primitive) {
    const Json* extensions = member(primitive, "extensions");
    return extensions ? member(*extensions, kDraco) : nullptr;
  }

  // Decodes the compressed data of every instanced mesh at once, in one child process however
  // many primitives there are (a process each would make a GLB of many small primitives slow).
  // Primitives whose references are broken are left out: mesh() reports them.
  void decode_draco_primitives() {
    std::vector<char> seen(cache_.size(), 0);
    std::vector<DracoKey> keys;
    std::vector<DracoRequest> requests;
    for (const Instance& instance : instances_) {
      if (seen[static_cast<std::size_t>(instance.mesh)]++) continue;
      for (const Json& primitive : *member(at("meshes", instance.mesh), "primitives")) {
        const Json* draco = draco_extension(primitive);
        if (!draco || !member(primitive, "attributes")) continue;
        const Result<DracoKey> key = draco_key(primitive, *draco, "");
        if (!key || draco_.count(*key)) continue;
        draco_.emplace(*key, Error{""});
        keys.push_back(*key);
        requests.push_back({view_bytes(key->first), key->second});
      }
    }
    std::vector<Result<DracoMesh>> decoded = decode_draco_all(requests);
    for (std::size_t i = 0; i < keys.size(); ++i) draco_.at(keys[i]) = std::move(decoded[i]);
  }

  // A KHR_draco_mesh_compression primitive: its buffer view as decoded by Draco.
  Result<const DracoMesh*> draco_primitive(const Json& primitive, const Json& draco,
                                           const std::string& where) const {
    const Result<DracoKey> key = draco_key(primitive, draco, where);
    if (!key) return key.error();
    const auto decoded = draco_.find(*key);
    LV_CHECK(decoded != draco_.end());  // decode_draco_primitives covered every instanced mesh
    if (!decoded->second)
      return fail(where + ": " + kDraco + " data: " + decoded->second.error().message);
    return &*decoded->second;
  }

  // A plain primitive: POSITION and optional indices, as triangles, a strip or a fan.
  Result<DracoMesh> plain_primitive(const Json& primitive, const std::string& where) const {
    const Result<std::int64_t> position =
        position_accessor(*member(primitive, "attributes"), where);
    if (!position) return position.error();
    const Result<Accessor> positions = accessor(*position);
    if (!positions) return positions.error();
    DracoMesh out;
    out.mesh.positions.resize(3 * positions->count);
    for (std::size_t v = 0; v < positions->count; ++v)
      std::memcpy(&out.mesh.positions[3 * v], positions->data + v * positions->stride, 12);

    std::vector<std::uint32_t> order;  // the vertices in primitive order
    if (const Json* indices = member(primitive, "indices")) {
      if (!indices->is_number_integer()) return fail(where + ": indices is not an accessor index");
      if (Status s = reference(primitive, "indices", "accessors", where); !s) return s.error();
      const Result<Accessor> view = accessor(indices->get<std::int64_t>());
      if (!view) return view.error();
      const int size = component_size(view->component_type);
      if (view->components != 1 || view->component_type == 5120 || view->component_type == 5122 ||
          view->component_type == 5126)
        return fail(where + ": indices are not unsigned integer scalars");
      order.resize(view->count);
      for (std::size_t i = 0; i < view->count; ++i) {
        const char* at = view->data + i * view->stride;
        std::uint32_t value = 0;
        if (size == 1) value = static_cast<std::uint8_t>(*at);
        if (size == 2) {
          std::uint16_t v16 = 0;
          std::memcpy(&v16, at, 2);
          value = v16;
        }
        if (size == 4) std::memcpy(&value, at, 4);
        if (value >= positions->count)
          return fail(where + ": index " + std::to_string(i) + " is " + std::to_string(value) +
                      ", but its attributes have " + std::to_string(positions->count) +
                      " elements");
        order[i] = value;
      }
    } else {
      order.resize(positions->count);
      for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<std::uint32_t>(i);
    }

    std::vector<std::uint32_t>& tris = out.mesh.indices;
    const std::int64_t mode = integer(primitive, "mode", 4);
    const std::size_t n = order.size();
    if (mode == 4) {
      if (n % 3 != 0)
        return fail(where + ": " + std::to_string(n) + " vertices do not make whole triangles");
      tris = std::move(order);
    } else if (mode == 5 ||
               mode == 6) {  // strip: (i, i+1, i+2), every other one reversed; fan: (0, i+1, i+2)
      if (n < 3) return fail(where + ": a strip or fan of " + std::to_string(n) + " vertices");
      tris.reserve(3 * (n - 2));
      for (std::size_t i = 0; i + 2 < n; ++i) {
        if (mode == 5)
          tris.insert(tris.end(), {order[i], order[i + 1 + i % 2], order[i + 2 - i % 2]});
        else
          tris.insert(tris.end(), {order[i + 1], order[i + 2], order[0]});
      }
    } else {
      return fail(where + ": mode " + std::to_string(mode) +
                  " is not triangles (4), a strip (5) or a fan (6)");
    }
    return out;
  }

  // Mesh `m`'s primitives, decoded once however many nodes name it.
  Result<const DracoMesh*> mesh(std::int64_t m) {
    std::optional<DracoMesh>& cached = cache_[static_cast<std::size_t>(m)];
    if (cached) return &*cached;
    DracoMesh all;
    const Json& primitives = *member(at("meshes", m), "primitives");
    for (std::size_t p = 0; p < primitives.size(); ++p) {
      const Json& primitive = primitives[p];
      const std::string where = "mesh " + std::to_string(m) + " primitive " + std::to_string(p);
      const Json* attributes = member(primitive, "attributes");
      if (!attributes || !attributes->is_object()) return fail(where + " has no attributes");
      const Json* draco = draco_extension(primitive);
      Result<DracoMesh> plain = Error{""};
      const DracoMesh* part = nullptr;
      if (draco) {
        const Result<const DracoMesh*> decoded = draco_primitive(primitive, *draco, where);
        if (!decoded) return decoded.error();
        part = *decoded;
      } else {
        plain = plain_primitive(primitive, where);
        if (!plain) return plain.error();
        part = &*plain;
      }
      if (all.mesh.num_vertices() + part->mesh.num_vertices() >=
          std::numeric_limits<std::uint32_t>::max())
        return fail("mesh " + std::to_string(m) + " has too many vertices");
      const auto base = static_cast<std::uint32_t>(all.mesh.num_vertices());
      all.mesh.positions.insert(all.mesh.positions.end(), part->mesh.positions.begin(),
                                part->mesh.positions.end());
      for (const std::uint32_t v : part->mesh.indices) all.mesh.indices.push_back(base + v);
      all.step = std::max(all.step, part->step);
    }
    cached = std::move(all);
    return &*cached;
  }

  // A node's local transform: its matrix (column-major), else translation · rotation · scale.
  Result<Eigen::Matrix4d> local_transform(const Json& node, const std::string& where) const {
    const auto numbers = [&](const char* key, std::size_t count, double* out) -> Status {
      const Json* m = member(node, key);
      if (!m) return {};
      if (!m->is_array() || m->size() != count ||
          !std::all_of(m->begin(), m->end(), [](const Json& x) { return x.is_number(); }))
        return fail(where + ": '" + key + "' is not " + std::to_string(count) + " numbers");
      for (std::size_t i = 0; i < count; ++i) out[i] = (*m)[i].get<double>();
      return {};
    };
    Eigen::Matrix4d transform = Eigen::Matrix4d::Identity();
    if (member(node, "matrix")) {
      if (Status s = numbers("matrix", 16, transform.data()); !s)
        return s.error();  // Eigen is column-major too
      return transform;
    }
    double t[3] = {0, 0, 0}, r[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1};
    for (const auto& [key, count, out] :
         {std::tuple{"translation", 3, t}, {"rotation", 4, r}, {"scale", 3, s}})
      if (Status st = numbers(key, static_cast<std::size_t>(count), out); !st) return st.error();
    Eigen::Quaterniond rotation(r[3], r[0], r[1], r[2]);  // glTF stores x, y, z, w
    if (!(rotation.norm() > 0) || !std::isfinite(rotation.norm()))
      return fail(where + ": 'rotation' is not a rotation");
    rotation.normalize();
    transform.topLeftCorner<3, 3>() =
        rotation.toRotationMatrix() * Eigen::Vector3d(s[0], s[1], s[2]).asDiagonal();
    transform.topRightCorner<3, 1>() = Eigen::Vector3d(t[0], t[1], t[2]);
    return transform;
  }

  // The nodes of scene `scene`, depth first without recursion; each node at most once.
  Status traverse(std::int64_t scene) {
    const Json* roots = member(at("scenes", scene), "nodes");
    if (!roots) return {};
    std::vector<char> visited(static_cast<std::size_t>(array_size("nodes")), 0);
    std::vector<std::pair<std::int64_t, Eigen::Matrix4d>> stack;
    for (auto it = roots->rbegin(); it != roots->rend(); ++it)
      stack.emplace_back(it->get<std::int64_t>(), Eigen::Matrix4d::Identity());
    while (!stack.empty()) {
      const auto [index, parent] = stack.back();
      stack.pop_back();
      const std::string where = "node " + std::to_string(index);
      if (visited[static_cast<std::size_t>(index)]++)
        return fail(where + " is reached twice from scene " + std::to_string(scene) +
                    ": the nodes do not form trees");
      const Json& node = at("nodes", index);
      const Result<Eigen::Matrix4d> local = local_transform(node, where);
      if (!local) return local.error();
      const Eigen::Matrix4d world = parent * *local;
      if (const Json* m = member(node, "mesh"))
        instances_.push_back({m->get<std::int64_t>(), world});
      if (const Json* children = member(node, "children"))
        for (auto it = children->rbegin(); it != children->rend(); ++it)
          stack.emplace_back(it->get<std::int64_t>(), world);
    }
    return {};
  }

  // Decodes the instanced meshes and bounds what they add up to before anything is copied:
  // instancing multiplies triangles without taking bytes.
  Status check_size() {
    std::uint64_t triangles = 0, vertices = 0;
    for (const Instance& instance : instances_) {
      const Result<const DracoMesh*> decoded = mesh(instance.mesh);
      if (!decoded) return decoded.error();
      triangles += (*decoded)->mesh.num_triangles();
      vertices += (*decoded)->mesh.num_vertices();
    }
    const std::uint64_t limit = 256 * static_cast<std::uint64_t>(bytes_.size());
    if (triangles > limit || vertices > limit ||
        vertices >= std::numeric_limits<std::uint32_t>::max())
      return fail(std::to_string(instances_.size()) + " mesh instances add up to " +
                  std::to_string(triangles) + " triangles and " + std::to_string(vertices) +
                  " vertices, more than 256 per byte of the file");
    // The arrays, and the copy welding makes of them.
    return check_memory(2 * 12 * (triangles + vertices), path_,
                        "assembling " + std::to_string(triangles) + " triangles");
  }

  // Appends an instance of `part` moved by `transform`.
  void emit(const DracoMesh& decoded, const Eigen::Matrix4d& transform) {
    const Mesh& part = decoded.mesh;
    const auto base = static_cast<std::uint32_t>(out_.mesh.num_vertices());
    std::vector<float>& positions = out_.mesh.positions;
    if (transform.isIdentity(0)) {
      positions.insert(positions.end(), part.positions.begin(), part.positions.end());
    } else {
      for (std::size_t v = 0; v < part.num_vertices(); ++v) {
        const Eigen::Vector4d p(part.positions[3 * v], part.positions[3 * v + 1],
                                part.positions[3 * v + 2], 1.0);
        const Eigen::Vector4d q = transform * p;
        positions.insert(positions.end(), {static_cast<float>(q[0]), static_cast<float>(q[1]),
                                           static_cast<float>(q[2])});
      }
    }
    // A mirroring transform turns counter-clockwise faces clockwise (glTF 2.0, "Transformations").
    const bool mirrored = transform.topLeftCorner<3, 3>().determinant() < 0;
    for (std::size_t t = 0; t < part.num_triangles(); ++t) {
      const auto [a, b, c] = part.triangle(t);
      out_.mesh.indices.insert(out_.mesh.indices.end(),
                               {base + a, base + (mirrored ? c : b), base + (mirrored ? b : c)});
    }
    // Each position moved by at most half a step per axis; after the transform, by the step
    // times the matrix's largest absolute row sum.
    const double gain = transform.topLeftCorner<3, 3>().cwiseAbs().rowwise().sum().maxCoeff();
    out_.step = std::max(out_.step, decoded.step * gain);
  }

  struct Instance {
    std::int64_t mesh;
    Eigen::Matrix4d transform;
  };

  std::string_view bytes_;
  const std::string& path_;
  Json doc_;
  std::string_view bin_;
  std::vector<std::optional<DracoMesh>> cache_;  // decoded meshes, by index
  std::map<DracoKey, Result<DracoMesh>> draco_;  // decoded compressed data
  std::vector<Instance> instances_;              // of the scene, in traversal order
  DracoMesh out_;
};

}  // namespace

Result<DracoMesh> read_glb(std::string_view bytes, const std::string& path) {
  return GlbReader(bytes, path).read();
}

}  // namespace lightvol::detail
