#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include <lightvol/core/check.h>
#include <lightvol/core/detail/json_keys.h>
#include <lightvol/light/light.h>
#include <lightvol/light/texel.h>

namespace lightvol {

std::string_view to_string(LightType type) {
  switch (type) {
    case LightType::spot:
      return "spot";
    case LightType::directional:
      return "directional";
    case LightType::omni:
      return "omni";
  }
  return "?";
}

std::string_view to_string(DepthEncoding encoding) {
  switch (encoding) {
    case DepthEncoding::window:
      return "window";
    case DepthEncoding::linear:
      return "linear";
    case DepthEncoding::radial:
      return "radial";
  }
  return "?";
}

namespace {

using nlohmann::json;

#define LV_TRY_ASSIGN(var, expr)                  \
  auto var##_result = (expr);                     \
  if (!var##_result) return var##_result.error(); \
  auto var = std::move(*var##_result)

constexpr const char* kAllKeys[] = {"type",   "position", "direction", "up",  "fov_y_deg",
                                    "aspect", "ortho",    "near",      "far", "depth",
                                    "flip_y", "view",     "projection"};

// Keys each type accepts in the parametric form; the matrix form swaps the geometric ones for
// "view" and "projection".
std::set<std::string> parametric_keys(LightType type) {
  switch (type) {
    case LightType::spot:
      return {"type",   "position", "direction", "up",    "fov_y_deg",
              "aspect", "near",     "far",       "depth", "flip_y"};
    case LightType::directional:
      return {"type", "position", "direction", "up", "ortho", "near", "far", "depth", "flip_y"};
    case LightType::omni:
      return {"type", "position", "near", "far", "depth", "flip_y"};
  }
  return {};
}

Result<LightType> parse_type(const KeyReader& keys) {
  LV_TRY_ASSIGN(name, keys.string("type"));
  if (name == "spot") return LightType::spot;
  if (name == "directional") return LightType::directional;
  if (name == "omni") return LightType::omni;
  return keys.error("type",
                    "expected \"spot\", \"directional\" or \"omni\", got " + quote_text(name));
}

Status parse_near_far(const KeyReader& keys, bool perspective, Light* light) {
  LV_TRY_ASSIGN(near, keys.number("near"));
  LV_TRY_ASSIGN(far, keys.number("far"));
  if (perspective && near <= 0)
    return keys.error("near", "must be > 0 for a perspective light, got " + format_number(near));
  if (!perspective && near < 0)
    return keys.error("near", "must be >= 0, got " + format_number(near));
  if (near >= far)
    return keys.error("far", "must be greater than near (" + format_number(near) + "), got " +
                                 format_number(far));
  light->near = near;
  light->far = far;
  return {};
}

// Position, direction and up into a view matrix, rejecting a zero direction and a zero or parallel
// up.
Status parse_frame(const KeyReader& keys, Light* light) {
  LV_TRY_ASSIGN(position, keys.vec3("position"));
  LV_TRY_ASSIGN(direction, keys.vec3("direction"));
  LV_TRY_ASSIGN(up, keys.vec3("up"));
  if (length(direction) == 0) return keys.error("direction", "must not be the zero vector");
  if (length(up) == 0) return keys.error("up", "must not be the zero vector");
  const Vec3d f = normalize(direction);
  const Vec3d u = normalize(up);
  if (length(cross(f, u)) < 1e-6) return keys.error("up", "must not be parallel to direction");
  light->position = position;
  light->direction = f;
  light->view = look_at(position, f, u);
  return {};
}

// The matrix form: "view" and "projection" replace the geometric keys.
Status parse_matrices(const KeyReader& keys, Light* light) {
  LV_TRY_ASSIGN(view, keys.matrix("view"));
  LV_TRY_ASSIGN(projection, keys.matrix("projection"));
  bool ok = false;
  const Mat4d inv_view = inverse(view, &ok);
  if (!ok) return keys.error("view", "is singular");
  if (view(3, 0) != 0 || view(3, 1) != 0 || view(3, 2) != 0 || view(3, 3) != 1)
    return keys.error("view", "must be affine: its last row must be [0, 0, 0, 1]");
  (void)inverse(projection, &ok);
  if (!ok) return keys.error("projection", "is singular");

  const Mat4d& p = projection;
  double near = 0, far = 0;
  if (light->type == LightType::spot) {
    if (p(3, 0) != 0 || p(3, 1) != 0 || p(3, 2) != -1 || p(3, 3) != 0)
      return keys.error("projection",
                        "a spot light needs an OpenGL perspective matrix: last row [0, 0, -1, 0]");
    near = p(2, 3) / (p(2, 2) - 1);
    far = p(2, 3) / (p(2, 2) + 1);
    if (!(near > 0) || !(far > near) || !std::isfinite(far))
      return keys.error("projection", "its near and far planes must satisfy 0 < near < far, got " +
                                          format_number(near) + " and " + format_number(far));
  } else {
    if (p(3, 0) != 0 || p(3, 1) != 0 || p(3, 2) != 0 || p(3, 3) != 1)
      return keys.error("projection",
                        "a directional light needs an orthographic matrix: last row [0, 0, 0, 1]");
    near = (p(2, 3) + 1) / p(2, 2);
    far = (p(2, 3) - 1) / p(2, 2);
    if (!(near >= 0) || !(far > near))
      return keys.error("projection", "its near and far planes must satisfy 0 <= near < far, got " +
                                          format_number(near) + " and " + format_number(far));
  }
  light->view = view;
  light->projection = projection;
  light->near = near;
  light->far = far;
  light->position = inv_view.transform_point({0, 0, 0});
  light->direction = normalize(inv_view.transform_vector({0, 0, -1}));
  return {};
}

}  // namespace

// Long (over 80 lines) on purpose: one check per key of LIGHT.json, in the order they are
// documented, each with its own message naming the key; a straight sequence.
Result<Light> parse_light(std::string_view json_text, const std::string& source) {
  Result<json> parsed = parse_json_object(json_text, source, "a light");
  if (!parsed) return parsed.error();
  const json& root = *parsed;
  const KeyReader keys(root, source);

  for (const auto& [key, value] : root.items()) {
    if (std::find(std::begin(kAllKeys), std::end(kAllKeys), key) == std::end(kAllKeys))
      return keys.error(key,
                        "unknown key (known: type, position, direction, up, fov_y_deg, "
                        "aspect, ortho, near, far, depth, flip_y, view, projection)");
  }

  Light light;
  LV_TRY_ASSIGN(type, parse_type(keys));
  light.type = type;

  const bool matrix_form = keys.has("view") || keys.has("projection");
  if (matrix_form && type == LightType::omni)
    return keys.error(keys.has("view") ? "view" : "projection",
                      "an omni light is given by position, near and far, not by matrices");
  std::set<std::string> allowed = parametric_keys(type);
  if (matrix_form) allowed = {"type", "view", "projection", "depth", "flip_y"};
  for (const auto& [key, value] : root.items()) {
    if (allowed.count(key)) continue;
    if (matrix_form && parametric_keys(type).count(key))
      return keys.error(key, "does not go with \"view\" and \"projection\", which replace it");
    return keys.error(key, "does not apply to a " + std::string(to_string(type)) + " light");
  }

  if (keys.has("depth")) {
    LV_TRY_ASSIGN(name, keys.string("depth"));
    if (name == "window")
      light.depth = DepthEncoding::window;
    else if (name == "linear")
      light.depth = DepthEncoding::linear;
    else if (name == "radial")
      light.depth = DepthEncoding::radial;
    else
      return keys.error("depth",
                        "expected \"window\", \"linear\" or \"radial\", got " + quote_text(name));
  }
  if (keys.has("flip_y")) {
    LV_TRY_ASSIGN(flip, keys.boolean("flip_y"));
    light.flip_y = flip;
  }

  if (matrix_form) {
    if (Status s = parse_matrices(keys, &light); !s) return s.error();
    return light;
  }

  switch (type) {
    case LightType::spot: {
      if (Status s = parse_frame(keys, &light); !s) return s.error();
      if (Status s = parse_near_far(keys, true, &light); !s) return s.error();
      LV_TRY_ASSIGN(fov, keys.number("fov_y_deg"));
      if (!(fov > 0 && fov < 180))
        return keys.error("fov_y_deg", "must lie in (0, 180) degrees, got " + format_number(fov));
      double aspect = 1.0;
      if (keys.has("aspect")) {
        LV_TRY_ASSIGN(a, keys.number("aspect"));
        if (!(a > 0)) return keys.error("aspect", "must be > 0, got " + format_number(a));
        aspect = a;
      }
      light.projection = perspective(fov, aspect, light.near, light.far);
      break;
    }
    case LightType::directional: {
      if (Status s = parse_frame(keys, &light); !s) return s.error();
      if (Status s = parse_near_far(keys, false, &light); !s) return s.error();
      LV_TRY_ASSIGN(o, keys.array4("ortho"));
      if (!(o[0] < o[1]) || !(o[2] < o[3]))
        return keys.error("ortho",
                          "extents [left, right, bottom, top] must have left < right and "
                          "bottom < top, got [" +
                              format_number(o[0]) + ", " + format_number(o[1]) + ", " +
                              format_number(o[2]) + ", " + format_number(o[3]) + "]");
      light.projection = orthographic(o[0], o[1], o[2], o[3], light.near, light.far);
      break;
    }
    case LightType::omni: {
      LV_TRY_ASSIGN(position, keys.vec3("position"));
      if (Status s = parse_near_far(keys, true, &light); !s) return s.error();
      light.position = position;
      light.direction = {0, 0, -1};
      Mat4d translate;
      translate.m = {1, 0, 0, -position.x, 0, 1, 0, -position.y, 0, 0, 1, -position.z, 0, 0, 0, 1};
      light.view = translate;
      light.projection = perspective(90.0, 1.0, light.near, light.far);
      break;
    }
  }
  return light;
}

Result<Light> load_light(const std::string& path) {
  Result<std::string> text = read_text_file(path, "light description");
  if (!text) return text.error();
  return parse_light(*text, path);
}

std::string_view omni_face_tag(int face) {
  static constexpr std::string_view tags[kOmniFaces] = {"px", "nx", "py", "ny", "pz", "nz"};
  LV_CHECK(face >= 0 && face < kOmniFaces);
  return tags[face];
}

std::string aspect_mismatch(const Light& light, int width, int height) {
  if (light.type == LightType::omni || width < 1 || height < 1) return {};
  // Half-width and half-height of the view at unit distance (perspective) or in eye units
  // (orthographic) are 1/P00 and 1/P11: the aspect is P11/P00.
  const double aspect = std::abs(light.projection(1, 1) / light.projection(0, 0));
  if (!std::isfinite(aspect) || aspect <= 0) return {};
  const double w = width, h = height;
  if (std::abs(w / aspect - h) <= 1 || std::abs(h * aspect - w) <= 1) return {};
  std::ostringstream note;
  note << "the image is " << width << "x" << height << " (aspect " << w / h
       << ") but the light's view has aspect " << aspect
       << ": texels are not square; is the light's \"aspect\" (or ortho) the image's?";
  return note.str();
}

Light light_in_space(const Light& light, Space space) {
  if (space == Space::world) return light;
  Light out = light;
  out.position = {0, 0, 0};
  // Omni light space keeps world axes; spot and directional look down their eye space's −Z.
  if (light.type != LightType::omni) out.direction = {0, 0, -1};
  out.view = Mat4d::identity();
  return out;
}

EyeBox light_eye_box(const Light& light) {
  if (light.type == LightType::omni)
    return {{-light.far, -light.far, -light.far}, {light.far, light.far, light.far}};
  bool ok = false;
  const Mat4d inv = inverse(light.projection, &ok);
  LV_CHECK(ok);
  EyeBox box{{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
  for (int k = 0; k < 8; ++k) {
    const Vec3d c =
        inv.transform_point({k & 1 ? 1.0 : -1.0, k & 2 ? 1.0 : -1.0, k & 4 ? 1.0 : -1.0});
    box.lo = {std::min(box.lo.x, c.x), std::min(box.lo.y, c.y), std::min(box.lo.z, c.z)};
    box.hi = {std::max(box.hi.x, c.x), std::max(box.hi.y, c.y), std::max(box.hi.z, c.z)};
  }
  if (light.is_perspective()) box.hi.z = 0;
  return box;
}

Mat4d omni_face_view(const Light& light, int face) {
  static constexpr Vec3d look[kOmniFaces] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                             {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
  static constexpr Vec3d up[kOmniFaces] = {{0, -1, 0}, {0, -1, 0}, {0, 0, 1},
                                           {0, 0, -1}, {0, -1, 0}, {0, -1, 0}};
  LV_CHECK(face >= 0 && face < kOmniFaces);
  return look_at(light.position, look[face], up[face]);
}

// ---- Unprojector --------------------------------------------------------------------------------

Unprojector::Unprojector(const Light& light, int width, int height, int face, Space space)
    : depth_(light.depth),
      perspective_(light.is_perspective()),
      flip_y_(light.flip_y),
      width_(width),
      height_(height) {
  LV_CHECK(width >= 2 && height >= 2);
  bool ok = false;
  inv_projection_ = inverse(light.projection, &ok);
  LV_CHECK(ok);
  Mat4d view = light.type == LightType::omni ? omni_face_view(light, face) : light.view;
  // Light space of an omni light keeps world axes with the origin at the light.
  const Mat4d eye_to_world = inverse(view, &ok);
  LV_CHECK(ok);
  if (space == Space::world) {
    to_out_ = eye_to_world;
  } else if (light.type == LightType::omni) {
    to_out_ = light.view * eye_to_world;
  } else {
    to_out_ = Mat4d::identity();
  }
  clip_to_out_ = to_out_ * inv_projection_;

  // Winding: the triangle of the near-plane points of texels (0,0), (1,0), (0,1) must face away
  // from the light (its normal along −Z in eye space); a mirroring output transform flips that.
  const Vec3d a = eye_near(0, 0), b = eye_near(1, 0), c = eye_near(0, 1);
  const double facing = -cross(b - a, c - a).z;
  LV_CHECK(facing != 0);
  double det3 = 0;
  {
    const Mat4d& m = to_out_;
    det3 = m(0, 0) * (m(1, 1) * m(2, 2) - m(1, 2) * m(2, 1)) -
           m(0, 1) * (m(1, 0) * m(2, 2) - m(1, 2) * m(2, 0)) +
           m(0, 2) * (m(1, 0) * m(2, 1) - m(1, 1) * m(2, 0));
  }
  standard_winding_ = (facing > 0) == (det3 > 0);

  if (light.type == LightType::directional) {
    // Every vertex of the volume lies in the box of the corner texels' near and far points.
    double max_abs = 0;
    for (const int col : {0, width - 1})
      for (const int row : {0, height - 1})
        for (const Vec3d& p : {near_point(col, row), far_point(col, row)})
          max_abs = std::max({max_abs, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
    const double ray_length = length(far_point(0, 0) - near_point(0, 0));
    LV_CHECK(ray_length > 0);
    min_t_ = std::min(0.5, std::ldexp(max_abs, -23 + 6) / ray_length);
  }
}

Error unreachable_radial_depth(const std::string& source, int col, int row, double depth) {
  return Error{source + ": pixel (" + std::to_string(col) + ", " + std::to_string(row) +
               "): radial depth " + std::to_string(depth) +
               " is shorter than the texel ray's distance from the light position"};
}

Vec3d Unprojector::ndc(int col, int row) const {
  return {texel_ndc_x(col, width_), texel_ndc_y(row, height_, flip_y_), 0};
}

Vec3d Unprojector::eye_near(int col, int row) const {
  const Vec3d n = ndc(col, row);
  return inv_projection_.transform_point({n.x, n.y, -1});
}

Vec3d Unprojector::eye_far(int col, int row) const {
  const Vec3d n = ndc(col, row);
  return inv_projection_.transform_point({n.x, n.y, 1});
}

Vec3d Unprojector::near_point(int col, int row) const {
  return to_out_.transform_point(eye_near(col, row));
}

Vec3d Unprojector::far_point(int col, int row) const {
  return to_out_.transform_point(eye_far(col, row));
}

int Unprojector::row_points(int row, const float* depths, float* out) const {
  int first_bad = -1;
  if (depth_ == DepthEncoding::window) {
    // clip_to_out · (x, y, z, 1) with y fixed along the row and x stepping by 2/W.
    const Mat4d& m = clip_to_out_;
    const double y = ndc(0, row).y;
    double base[4], dx[4], dz[4];
    for (int i = 0; i < 4; ++i) {
      base[i] = m(i, 1) * y + m(i, 3) - m(i, 2) + m(i, 0) * (1.0 / width_ - 1.0);
      dx[i] = m(i, 0) * (2.0 / width_);
      dz[i] = 2.0 * m(i, 2);  // z_ndc = 2d − 1: the −1 is folded into base
    }
    for (int c = 0; c < width_; ++c) {
      const double d = std::clamp(static_cast<double>(depths[c]), min_t_, 1.0);
      const double x = static_cast<double>(c);
      const double inv_w = 1.0 / (base[3] + dx[3] * x + dz[3] * d);
      for (int i = 0; i < 3; ++i)
        out[3 * c + i] = static_cast<float>((base[i] + dx[i] * x + dz[i] * d) * inv_w);
    }
    return first_bad;
  }
  for (int c = 0; c < width_; ++c) {
    Vec3d p;
    if (!point(c, row, depths[c], &p)) {
      if (first_bad < 0) first_bad = c;
      p = near_point(c, row);
    }
    out[3 * c] = static_cast<float>(p.x);
    out[3 * c + 1] = static_cast<float>(p.y);
    out[3 * c + 2] = static_cast<float>(p.z);
  }
  return first_bad;
}

bool Unprojector::point(int col, int row, double depth, Vec3d* out) const {
  if (depth_ == DepthEncoding::window) {
    const Vec3d n = ndc(col, row);
    // Window depth is linear along the ray only for orthographic projections, where min_t_ is set.
    const double z = 2.0 * std::clamp(depth, min_t_, 1.0) - 1.0;
    *out = clip_to_out_.transform_point({n.x, n.y, z});
    return true;
  }
  // Linear and radial depths: find the parameter t of the point on the near→far segment.
  const Vec3d pn = eye_near(col, row);
  const Vec3d pf = eye_far(col, row);
  const Vec3d dv = pf - pn;
  double t = 0;
  if (depth_ == DepthEncoding::linear) {
    t = (-depth - pn.z) / dv.z;
  } else {
    // |pn + t·dv| = depth, the far root (the ray leaves the light).
    const double a = dot(dv, dv), b = 2 * dot(pn, dv), c = dot(pn, pn) - depth * depth;
    double disc = b * b - 4 * a * c;
    if (disc < 0) {
      // A perspective ray starts at the light: every radial depth is reached, and one before the
      // near plane (0, 1e-20: a discriminant of 4·a·depth² that rounding may make negative) has
      // its far root at t ≤ 0, the near plane. Only a parallel ray can pass the light at a
      // distance greater than the depth.
      if (!perspective_) return false;
      disc = 0;
    }
    t = (-b + std::sqrt(disc)) / (2 * a);
  }
  t = std::clamp(t, min_t_, 1.0);
  *out = to_out_.transform_point(pn + t * dv);
  return true;
}

}  // namespace lightvol
