#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>

#include <draco/io/gltf_encoder.h>
#include <nlohmann/json.hpp>

#include <lightvol/core/check.h>
#include <lightvol/export/detail/glb_writer.h>
#include <lightvol/export/export.h>

namespace lightvol {

namespace {

using Json = nlohmann::json;

constexpr std::uint32_t kMagic = 0x46546C67u, kJsonChunk = 0x4E4F534Au;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

Json vec3(Vec3d v) { return Json::array({v.x, v.y, v.z}); }

Json rows(const Mat4d& m) {
  Json out = Json::array();
  for (int r = 0; r < 4; ++r) out.push_back({m(r, 0), m(r, 1), m(r, 2), m(r, 3)});
  return out;
}

// The unit quaternion (x, y, z, w) of the rotation whose columns are the unit vectors a, b, c.
Json quaternion(Vec3d a, Vec3d b, Vec3d c) {
  const double m00 = a.x, m10 = a.y, m20 = a.z, m01 = b.x, m11 = b.y, m21 = b.z, m02 = c.x,
               m12 = c.y, m22 = c.z;
  double x, y, z, w;
  const double trace = m00 + m11 + m22;
  if (trace > 0) {
    const double s = 0.5 / std::sqrt(trace + 1);
    w = 0.25 / s, x = (m21 - m12) * s, y = (m02 - m20) * s, z = (m10 - m01) * s;
  } else if (m00 > m11 && m00 > m22) {
    const double s = 2 * std::sqrt(1 + m00 - m11 - m22);
    w = (m21 - m12) / s, x = 0.25 * s, y = (m01 + m10) / s, z = (m02 + m20) / s;
  } else if (m11 > m22) {
    const double s = 2 * std::sqrt(1 + m11 - m00 - m22);
    w = (m02 - m20) / s, x = (m01 + m10) / s, y = 0.25 * s, z = (m12 + m21) / s;
  } else {
    const double s = 2 * std::sqrt(1 + m22 - m00 - m11);
    w = (m10 - m01) / s, x = (m02 + m20) / s, y = (m12 + m21) / s, z = 0.25 * s;
  }
  const double n = std::sqrt(x * x + y * y + z * z + w * w);
  if (w < 0) w = -w, x = -x, y = -y, z = -z;  // one of the two equal quaternions, always the same
  return {x / n, y / n, z / n, w / n};
}

// The light as lightvol reads it back (parse_light): the matrix form for spot and directional
// lights, which records any view and projection exactly; position, near and far for omni lights.
Json light_description(const Light& light) {
  Json out = {{"type", to_string(light.type)}};
  if (light.type == LightType::omni) {
    out["position"] = vec3(light.position);
    out["near"] = light.near;
    out["far"] = light.far;
  } else {
    out["view"] = rows(light.view);
    out["projection"] = rows(light.projection);
  }
  out["depth"] = to_string(light.depth);
  out["flip_y"] = light.flip_y;
  return out;
}

}  // namespace

detail::SpotCone detail::spot_cone(const Light& light) {
  LV_CHECK(light.type == LightType::spot);
  bool ok = false;
  const Mat4d inv = inverse(light.projection, &ok);
  LV_CHECK(ok);
  // The frustum's section at eye z = −1: the rectangle [l, r] × [b, t].
  const Vec3d lo = inv.transform_point({-1, -1, -1}), hi = inv.transform_point({1, 1, -1});
  const double l = std::min(lo.x / -lo.z, hi.x / -hi.z), r = std::max(lo.x / -lo.z, hi.x / -hi.z);
  const double b = std::min(lo.y / -lo.z, hi.y / -hi.z), t = std::max(lo.y / -lo.z, hi.y / -hi.z);
  SpotCone cone;
  const double far_x = std::max(-l, r), far_y = std::max(-b, t);
  cone.outer = std::atan(std::hypot(far_x, far_y));
  cone.inner = std::atan(std::max(0.0, std::min({-l, r, -b, t})));
  // glTF asks inner < outer; they are equal only for a degenerate (zero-width) frustum.
  cone.inner = std::min(cone.inner, std::nextafter(cone.outer, 0.0));
  return cone;
}

std::unique_ptr<draco::Mesh> detail::to_draco(const Mesh& mesh) {
  auto out = std::make_unique<draco::Mesh>();
  const std::size_t nv = mesh.num_vertices(), nt = mesh.num_triangles();
  out->set_num_points(static_cast<std::uint32_t>(nv));
  draco::GeometryAttribute position;
  position.Init(draco::GeometryAttribute::POSITION, nullptr, 3, draco::DT_FLOAT32, false,
                sizeof(float) * 3, 0);
  const int id = out->AddAttribute(position, true, static_cast<std::uint32_t>(nv));
  draco::PointAttribute* attribute = out->attribute(id);
  for (std::size_t v = 0; v < nv; ++v)
    attribute->SetAttributeValue(draco::AttributeValueIndex(static_cast<std::uint32_t>(v)),
                                 &mesh.positions[3 * v]);
  out->SetNumFaces(nt);
  for (std::size_t t = 0; t < nt; ++t) {
    draco::Mesh::Face face;
    for (int k = 0; k < 3; ++k) face[k] = draco::PointIndex(mesh.indices[3 * t + k]);
    out->SetFace(draco::FaceIndex(static_cast<std::uint32_t>(t)), face);
  }
  return out;
}

Status detail::check_draco_bits(int bits) {
  if (bits < 1 || bits > 30)
    return Error{"ExportOptions::draco_bits: must lie in 1..30, got " + std::to_string(bits)};
  return {};
}

Result<std::string> detail::annotate_glb(std::string_view glb, const GlbContent& content) {
  const auto u32 = [&](std::size_t at) {
    std::uint32_t v = 0;
    std::memcpy(&v, glb.data() + at, 4);
    return v;
  };
  // Draco's encoder wrote this; anything else is a broken invariant, not bad input.
  LV_CHECK(glb.size() >= 20 && u32(0) == kMagic && u32(16) == kJsonChunk);
  const std::size_t json_length = u32(12);
  LV_CHECK(json_length <= glb.size() - 20 && json_length % 4 == 0);
  Json doc = Json::parse(glb.substr(20, json_length));
  const std::string_view bin = glb.substr(20 + json_length);  // the BIN chunk, header and all

  // bufferView.target: vertex attributes live in ARRAY_BUFFERs, indices in ELEMENT_ARRAY_BUFFERs.
  // Draco-compressed primitives name accessors without buffer views: nothing to mark there.
  const auto mark = [&](const Json& accessor_index, int target) {
    const Json& accessor = doc["accessors"].at(accessor_index.get<std::size_t>());
    if (accessor.contains("bufferView"))
      doc["bufferViews"].at(accessor["bufferView"].get<std::size_t>())["target"] = target;
  };
  if (doc.contains("meshes"))
    for (const Json& mesh : doc["meshes"])
      for (const Json& primitive : mesh["primitives"]) {
        for (const auto& [name, accessor] : primitive["attributes"].items()) {
          (void)name;
          mark(accessor, kArrayBuffer);
        }
        if (primitive.contains("indices")) mark(primitive["indices"], kElementArrayBuffer);
      }

  if (content.light) {
    const Light& light = *content.light;
    Json medium;
    if (!content.medium_json.empty()) {
      medium = Json::parse(content.medium_json, nullptr, false);
      if (medium.is_discarded() || !medium.is_object())
        return Error{"the medium is not a JSON object"};
    }
    const double intensity =
        medium.is_object() && medium.contains("intensity") && medium["intensity"].is_number()
            ? medium["intensity"].get<double>()
            : 1.0;
    Json punctual = {{"name", "lightvol " + std::string(to_string(light.type)) + " light"},
                     {"color", {1.0, 1.0, 1.0}},
                     {"intensity", intensity}};
    Json node = {{"name", "light"}, {"translation", vec3(light.position)}};
    bool ok = false;
    const Mat4d eye_to_world = inverse(light.view, &ok);
    LV_CHECK(ok);
    if (light.type != LightType::omni) {
      // The node's −Z is the light's direction; its +Y the light's up, made orthogonal to it.
      const Vec3d z = -1.0 * normalize(light.direction);
      Vec3d up = eye_to_world.transform_vector({0, 1, 0});
      if (length(up - dot(up, z) * z) < 1e-9 * length(up))
        up = eye_to_world.transform_vector({1, 0, 0});
      const Vec3d y = normalize(up - dot(up, z) * z);
      node["rotation"] = quaternion(cross(y, z), y, z);
    }
    switch (light.type) {
      case LightType::spot: {
        const SpotCone cone = spot_cone(light);
        punctual["type"] = "spot";
        punctual["spot"] = {{"innerConeAngle", cone.inner}, {"outerConeAngle", cone.outer}};
        punctual["range"] = light.far / std::cos(cone.outer);  // the frustum's farthest corner
        break;
      }
      case LightType::directional:
        punctual["type"] = "directional";
        break;
      case LightType::omni:
        punctual["type"] = "point";
        punctual["range"] = light.far * std::numbers::sqrt3;  // the cube faces' farthest corner
        break;
    }
    Json extras = {{"light", light_description(light)}};
    if (medium.is_object()) extras["medium"] = medium;
    node["extras"] = {{"lightvol", extras}};
    node["extensions"] = {{"KHR_lights_punctual", {{"light", 0}}}};

    doc["extensions"]["KHR_lights_punctual"]["lights"] = Json::array({punctual});
    Json& used = doc["extensionsUsed"];
    if (!used.is_array()) used = Json::array();
    used.push_back("KHR_lights_punctual");
    Json& nodes = doc["nodes"];
    if (!nodes.is_array()) nodes = Json::array();
    const std::size_t light_node = nodes.size();
    nodes.push_back(node);
    if (!doc.contains("scenes") || doc["scenes"].empty()) {
      Json roots = Json::array();
      for (std::size_t n = 0; n < nodes.size(); ++n) roots.push_back(n);
      doc["scenes"] = Json::array({{{"nodes", roots}}});
      doc["scene"] = 0;
    } else {
      Json& scene = doc["scenes"].at(doc.value("scene", 0));
      scene["nodes"].push_back(light_node);
    }
  }

  std::string json = doc.dump(-1, ' ', false, Json::error_handler_t::replace);
  json.resize((json.size() + 3) & ~std::size_t{3}, ' ');
  std::string out(20, '\0');
  const auto put = [&](std::size_t at, std::uint32_t v) { std::memcpy(out.data() + at, &v, 4); };
  put(0, kMagic);
  put(4, 2);
  put(8, static_cast<std::uint32_t>(20 + json.size() + bin.size()));
  put(12, static_cast<std::uint32_t>(json.size()));
  put(16, kJsonChunk);
  out += json;
  out += bin;
  return out;
}

Result<std::string> encode_glb(const Mesh& mesh, bool draco, int bits, const GlbContent& content) {
  if (draco) {
    if (Status s = detail::check_draco_bits(bits); !s) return s.error();
  }
  auto dm = detail::to_draco(mesh);
  if (draco) {
    draco::DracoCompressionOptions compression;
    compression.quantization_position.SetQuantizationBits(bits);
    dm->SetCompressionEnabled(true);
    dm->SetCompressionOptions(compression);
  }
  draco::GltfEncoder encoder;
  draco::EncoderBuffer buffer;
  const draco::Status status = encoder.EncodeToBuffer(*dm, &buffer);
  if (!status.ok()) return Error{"glTF encoding failed: " + status.error_msg_string()};
  return detail::annotate_glb(std::string_view(buffer.data(), buffer.size()), content);
}

}  // namespace lightvol
