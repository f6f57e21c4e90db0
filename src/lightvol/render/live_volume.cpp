#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <limits>
#include <string>

#include <lightvol/core/check.h>
#include <lightvol/depth/cube_faces.h>
#include <lightvol/render/detail/airlight_glsl.h>
#include <lightvol/render/live_adaptive.h>
#include <lightvol/render/live_volume.h>
#include <lightvol/volume/omni_volume.h>
#include <lightvol/volume/static_volume.h>

namespace lightvol {

using namespace gl;

namespace {

// The uniforms of the live vertex stage for one light and map size, computed in double.
struct LiveUniforms {
  int width = 0, height = 0;
  int flip_y = 0, depth = 0, type = 0, standard = 1;
  float min_t = 0;
  float ray_x[4] = {}, ray_y[4] = {}, near_0[4] = {}, far_0[4] = {};
  float eye_to_world[kOmniFaces][16] = {};  // row-major; spot, directional: [0]
  float apex[3] = {}, cap[3] = {};
};

LiveUniforms live_uniforms(const Light& light, int width, int height) {
  const Unprojector unproject(light, width, height, 0, Space::world);
  LiveUniforms u;
  u.width = width;
  u.height = height;
  u.flip_y = light.flip_y ? 1 : 0;
  u.depth = static_cast<int>(light.depth);
  u.type = static_cast<int>(light.type);
  u.standard = unproject.standard_winding() ? 1 : 0;
  u.min_t = static_cast<float>(unproject.min_t());
  bool ok = false;
  const Mat4d inv_p = inverse(light.projection, &ok);
  LV_CHECK(ok);
  for (int i = 0; i < 4; ++i) {
    u.ray_x[i] = static_cast<float>(inv_p(i, 0));
    u.ray_y[i] = static_cast<float>(inv_p(i, 1));
    u.near_0[i] = static_cast<float>(inv_p(i, 3) - inv_p(i, 2));  // invP · (0, 0, −1, 1)
    u.far_0[i] = static_cast<float>(inv_p(i, 3) + inv_p(i, 2));   // invP · (0, 0, 1, 1)
  }
  for (int f = 0; f < (light.type == LightType::omni ? kOmniFaces : 1); ++f) {
    const Mat4d to_world =
        inverse(light.type == LightType::omni ? omni_face_view(light, f) : light.view, &ok);
    LV_CHECK(ok);
    for (int i = 0; i < 16; ++i) u.eye_to_world[f][i] = static_cast<float>(to_world.m[i]);
  }
  if (light.type == LightType::omni) return u;
  const Vec3d apex = unproject.apex();
  const Vec3d cap =
      0.25 * (unproject.near_point(0, 0) + unproject.near_point(width - 1, 0) +
              unproject.near_point(0, height - 1) + unproject.near_point(width - 1, height - 1));
  for (int k = 0; k < 3; ++k) {
    u.apex[k] = static_cast<float>(apex[k]);
    u.cap[k] = static_cast<float>(cap[k]);
  }
  return u;
}

bool is_depth_format(GLint format) {
  switch (format) {
    case GL_DEPTH_COMPONENT16:
    case GL_DEPTH_COMPONENT24:
    case GL_DEPTH_COMPONENT32:
    case GL_DEPTH_COMPONENT32F:
    case GL_DEPTH24_STENCIL8:
    case GL_DEPTH32F_STENCIL8:
      return true;
    default:
      return false;
  }
}

// Why `map` cannot be a shadow map of `light`, or "". `name` names it.
std::string map_problem(const Light& light, const GlShadowMap& map, const std::string& name) {
  if (map.width < 2 || map.height < 2)
    return name + ": size " + std::to_string(map.width) + "x" + std::to_string(map.height) +
           " given; a volume needs at least 2x2 texels";
  // Vertex ids are GLSL ints: W·H plus the closing must stay below 2^31.
  const VolumeCounts counts = light.type == LightType::omni
                                  ? static_volume_counts(light.type, map.width, map.width)
                                  : static_volume_counts(light.type, map.width, map.height);
  if (counts.vertices >= std::uint64_t{1} << 31 ||
      3 * counts.triangles >= std::uint64_t{std::numeric_limits<GLsizei>::max()})
    return name + ": " + std::to_string(map.width) + "x" + std::to_string(map.height) +
           " texels are more than one draw call holds";
  (void)pending_error();
  if (map.texture == 0 || glIsTexture(map.texture) != GL_TRUE) return name + ": not a texture name";
  glBindTexture(GL_TEXTURE_2D, map.texture);
  if (!pending_error().empty()) return name + ": not a 2D texture";
  GLint w = 0, h = 0, format = 0, compare = GL_NONE;
  glGetTexLevelParameteriv(GL_TEXTURE_2D, 0, GL_TEXTURE_WIDTH, &w);
  glGetTexLevelParameteriv(GL_TEXTURE_2D, 0, GL_TEXTURE_HEIGHT, &h);
  glGetTexLevelParameteriv(GL_TEXTURE_2D, 0, GL_TEXTURE_INTERNAL_FORMAT, &format);
  glGetTexParameteriv(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, &compare);
  glBindTexture(GL_TEXTURE_2D, 0);
  if (w != map.width || h != map.height)
    return name + ": level 0 is " + std::to_string(w) + "x" + std::to_string(h) + ", not the " +
           std::to_string(map.width) + "x" + std::to_string(map.height) + " given";
  const bool depth_format = is_depth_format(format);
  if (!depth_format && format != GL_R32F) {
    char hex[16];
    std::snprintf(hex, sizeof hex, "0x%04X", static_cast<unsigned>(format));
    return name + ": internal format " + hex + " is neither a depth format nor GL_R32F";
  }
  if (depth_format && light.depth != DepthEncoding::window)
    return name + ": a depth texture holds window depth in [0, 1]; the light's \"depth\" is \"" +
           std::string(to_string(light.depth)) + "\", which needs a GL_R32F texture";
  if (depth_format && compare != GL_NONE)
    return name + ": GL_TEXTURE_COMPARE_MODE is on; texelFetch needs it GL_NONE";
  return "";
}

std::string stage_source(const char* stage) {
  return "#version 450 core\n#define " + std::string(stage) + "\n" + detail::kAirlightGlsl;
}

}  // namespace

gl::TextureHandle upload_shadow_map(const Light& light, const DepthImage& depth) {
  const std::size_t w = static_cast<std::size_t>(depth.width);
  const int h = depth.height;
  std::vector<float> rows(depth.values.size());
  for (int t = 0; t < h; ++t) {
    // GL row t (t = 0 at the bottom, NDC y = −1) is image row H − 1 − t, or t with flip_y.
    const int row = light.flip_y ? t : h - 1 - t;
    std::copy_n(depth.values.begin() + static_cast<std::ptrdiff_t>(row * w), w,
                rows.begin() + static_cast<std::ptrdiff_t>(t * w));
  }
  return make_texture_2d(depth.width, h, GL_R32F, rows.data(), 1);
}

namespace {

// Why `maps` cannot be the shadow maps of `light`, or "".
std::string maps_problem(const Light& light, const std::vector<GlShadowMap>& maps) {
  const bool omni = light.type == LightType::omni;
  const std::size_t expected = omni ? kOmniFaces : 1;
  if (maps.size() != expected)
    return "live volume: " + std::string(to_string(light.type)) + " lights need " +
           std::to_string(expected) + (omni ? " shadow maps (their cube faces)" : " shadow map") +
           ", got " + std::to_string(maps.size());
  for (std::size_t f = 0; f < maps.size(); ++f) {
    const GlShadowMap& map = maps[f];
    const std::string name = "shadow map texture " + std::to_string(map.texture) +
                             (omni ? " (face " + omni_face_name(static_cast<int>(f)) + ")" : "");
    if (omni && (map.width != map.height || map.width != maps[0].width))
      return name + ": " + std::to_string(map.width) + "x" + std::to_string(map.height) +
             "; omni faces are square and all of one size (face " + omni_face_name(0) + " is " +
             std::to_string(maps[0].width) + "x" + std::to_string(maps[0].height) + ")";
    if (std::string problem = map_problem(light, map, name); !problem.empty()) return problem;
  }
  return "";
}

}  // namespace

struct LiveVolume::State {
  Light light;
  std::vector<GlShadowMap> maps;
  LiveUniforms uniforms;
  Program capture;
  VertexArrayHandle vao;       // no attributes; the triangles (drawn by the live vertex stage)
  VertexArrayHandle mesh_vao;  // attribute 0: positions; the triangles
  BufferHandle indices, positions;
  Framebuffer target;  // 1×1: a draw needs a complete framebuffer even with rasterization off
  GLsizei index_count = 0;
  std::uint64_t vertices = 0, triangles = 0;
  std::unique_ptr<detail::LiveAdaptive> adaptive;  // set: LiveOptions::max_error
};

LiveVolume::~LiveVolume() = default;

Result<std::unique_ptr<LiveVolume>> LiveVolume::create(const Light& light,
                                                       const std::vector<GlShadowMap>& maps,
                                                       const LiveOptions& options) {
  // The adaptive volume's compute shaders need compute (OpenGL 4.3, within 4.5).
  if (Status st = require_context(4, 5, options.max_error.has_value(),
                                  options.max_error ? "adaptive live volume" : "live volume");
      !st)
    return st.error();
  std::unique_ptr<LiveVolume> live(new LiveVolume());
  live->state_ = std::make_unique<State>();
  State& s = *live->state_;
  s.light = light;
  if (const std::string problem = maps_problem(light, maps); !problem.empty())
    return Error{problem};
  if (options.max_error) {
    const double e = *options.max_error;
    if (!std::isfinite(e) || e < 0)
      return Error{"live volume: max_error: expected a finite number >= 0, got " +
                   std::to_string(e)};
    if (options.max_rounds < 1 || options.max_rounds > 63)
      return Error{"live volume: max_rounds: expected 1 to 63, got " +
                   std::to_string(options.max_rounds)};
    if (options.max_seam_rounds < 1 || options.max_seam_rounds > 64)
      return Error{"live volume: max_seam_rounds: expected 1 to 64, got " +
                   std::to_string(options.max_seam_rounds)};
    if (std::string problem = detail::live_adaptive_problem(light); !problem.empty())
      return Error{problem};
    Result<std::unique_ptr<detail::LiveAdaptive>> adaptive =
        detail::LiveAdaptive::create(e, options.max_rounds, options.max_seam_rounds);
    if (!adaptive) return adaptive.error();
    s.adaptive = std::move(*adaptive);
  }
  Result<Program> capture =
      Program::compile(stage_source("LIGHTVOL_LIVE_VOLUME_VERTEX"),
                       "#version 450 core\nout vec4 colour;\nvoid main() { colour = vec4(0.0); }\n",
                       "live volume capture", {"world"});
  if (!capture) return capture.error();
  s.capture = std::move(*capture);
  GLuint id = 0;
  glGenVertexArrays(1, &id);
  s.vao = VertexArrayHandle(id);
  glGenVertexArrays(1, &id);
  s.mesh_vao = VertexArrayHandle(id);
  glGenBuffers(1, &id);
  s.indices = BufferHandle(id);
  glGenBuffers(1, &id);
  s.positions = BufferHandle(id);
  glBindVertexArray(s.vao.id());
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, s.indices.id());
  glBindVertexArray(s.mesh_vao.id());
  glBindBuffer(GL_ARRAY_BUFFER, s.positions.id());
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  glEnableVertexAttribArray(0);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, s.indices.id());
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  Result<Framebuffer> target = Framebuffer::create(1, 1, {GL_R32F}, false);
  if (!target) return target.error();
  s.target = std::move(*target);
  if (Status st = live->set_shadow_maps(maps); !st) return st.error();
  return live;
}

Status LiveVolume::set_shadow_maps(const std::vector<GlShadowMap>& maps) {
  State& s = *state_;
  if (const std::string problem = maps_problem(s.light, maps); !problem.empty())
    return Error{problem};
  const bool resized =
      s.maps.empty() || maps[0].width != s.maps[0].width || maps[0].height != s.maps[0].height;
  s.maps = maps;
  if (!resized) return {};
  const int w = maps[0].width, h = maps[0].height;
  s.uniforms = live_uniforms(s.light, w, h);
  if (s.adaptive) {
    if (Status st = s.adaptive->resize(s.light, w, h); !st) return st;
    s.vertices = s.adaptive->max_vertices();
    s.triangles = s.adaptive->max_triangles();
    s.index_count = 0;
    return {};
  }
  const bool omni = s.light.type == LightType::omni;
  const std::vector<std::uint32_t> indices =
      omni ? omni_volume_indices(s.light, w) : static_volume_indices(s.light, w, h);
  glBindVertexArray(s.vao.id());
  glBufferData(GL_ELEMENT_ARRAY_BUFFER,
               static_cast<GLsizeiptr>(indices.size() * sizeof(std::uint32_t)), indices.data(),
               GL_STATIC_DRAW);
  glBindVertexArray(0);
  s.index_count = static_cast<GLsizei>(indices.size());
  const VolumeCounts counts = static_volume_counts(s.light.type, w, h);
  s.vertices = counts.vertices;
  s.triangles = counts.triangles;
  glBindBuffer(GL_ARRAY_BUFFER, s.positions.id());
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(3 * s.vertices * sizeof(float)), nullptr,
               GL_DYNAMIC_COPY);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  if (std::string e = pending_error(); !e.empty())
    return Error{"OpenGL: uploading the live volume's triangles: " + e};
  return {};
}

Status LiveVolume::validate() const {
  const State& s = *state_;
  if (Status st = require_context(4, 5, false, "live volume"); !st) return st;
  if (const std::string problem = maps_problem(s.light, s.maps); !problem.empty())
    return Error{problem};
  const bool omni = s.light.type == LightType::omni;
  for (std::size_t f = 0; f < s.maps.size(); ++f) {
    const GlShadowMap& map = s.maps[f];
    GLint format = 0;
    glBindTexture(GL_TEXTURE_2D, map.texture);
    glGetTexLevelParameteriv(GL_TEXTURE_2D, 0, GL_TEXTURE_INTERNAL_FORMAT, &format);
    std::vector<float> rows(static_cast<std::size_t>(map.width) * map.height);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glGetTexImage(GL_TEXTURE_2D, 0, is_depth_format(format) ? GL_DEPTH_COMPONENT : GL_RED, GL_FLOAT,
                  rows.data());
    glBindTexture(GL_TEXTURE_2D, 0);
    if (std::string e = pending_error(); !e.empty())
      return Error{"OpenGL: reading shadow map texture " + std::to_string(map.texture) + ": " + e};
    DepthImage image;
    image.width = map.width;
    image.height = map.height;
    image.values.resize(rows.size());
    const std::size_t w = static_cast<std::size_t>(map.width);
    for (int t = 0; t < map.height; ++t) {
      const int row = s.light.flip_y ? t : map.height - 1 - t;  // as upload_shadow_map stores it
      std::copy_n(rows.begin() + static_cast<std::ptrdiff_t>(t * w), w,
                  image.values.begin() + static_cast<std::ptrdiff_t>(row * w));
    }
    const std::string name =
        "shadow map texture " + std::to_string(map.texture) +
        (omni ? " (face " + omni_face_name(static_cast<int>(f)) + ")" : std::string());
    if (Status st = validate_depths(image, name); !st) return st;
  }
  return {};
}

const Light& LiveVolume::light() const { return state_->light; }
const std::vector<GlShadowMap>& LiveVolume::shadow_maps() const { return state_->maps; }
std::uint64_t LiveVolume::num_vertices() const { return state_->vertices; }
std::uint64_t LiveVolume::num_triangles() const { return state_->triangles; }
GLsizei LiveVolume::index_count() const { return state_->index_count; }
bool LiveVolume::adaptive() const { return state_->adaptive != nullptr; }

void LiveVolume::bind(const Program& program, int unit) const {
  const State& s = *state_;
  const LiveUniforms& u = s.uniforms;
  glUniform2i(program.uniform("live_size"), u.width, u.height);
  glUniform1i(program.uniform("live_flip_y"), u.flip_y);
  glUniform1i(program.uniform("live_depth"), u.depth);
  glUniform1i(program.uniform("live_type"), u.type);
  glUniform1i(program.uniform("live_standard"), u.standard);
  glUniform1f(program.uniform("live_min_t"), u.min_t);
  glUniform4f(program.uniform("live_ray_x"), u.ray_x[0], u.ray_x[1], u.ray_x[2], u.ray_x[3]);
  glUniform4f(program.uniform("live_ray_y"), u.ray_y[0], u.ray_y[1], u.ray_y[2], u.ray_y[3]);
  glUniform4f(program.uniform("live_near_0"), u.near_0[0], u.near_0[1], u.near_0[2], u.near_0[3]);
  glUniform4f(program.uniform("live_far_0"), u.far_0[0], u.far_0[1], u.far_0[2], u.far_0[3]);
  glUniformMatrix4fv(program.uniform("live_eye_to_world"), kOmniFaces, GL_TRUE,
                     &u.eye_to_world[0][0]);
  glUniform3f(program.uniform("live_apex"), u.apex[0], u.apex[1], u.apex[2]);
  glUniform3f(program.uniform("live_cap"), u.cap[0], u.cap[1], u.cap[2]);
  // Every element of the sampler array on a unit of its own; a spot's or directional light's one
  // map on all six (only element 0 is read).
  static constexpr const char* kSamplers[kOmniFaces] = {"shadow_maps[0]", "shadow_maps[1]",
                                                        "shadow_maps[2]", "shadow_maps[3]",
                                                        "shadow_maps[4]", "shadow_maps[5]"};
  for (int f = 0; f < kOmniFaces; ++f) {
    const GlShadowMap& map = s.maps[s.maps.size() == 1 ? 0 : static_cast<std::size_t>(f)];
    glUniform1i(program.uniform(kSamplers[f]), unit + f);
    glActiveTexture(static_cast<GLenum>(GL_TEXTURE0 + unit + f));
    glBindTexture(GL_TEXTURE_2D, map.texture);
  }
  glBindVertexArray(s.vao.id());
}

GLuint LiveVolume::mesh_vertex_array() const {
  return state_->adaptive ? state_->adaptive->vertex_array() : state_->mesh_vao.id();
}

void LiveVolume::draw_mesh() const {
  const State& s = *state_;
  if (s.adaptive) {
    s.adaptive->draw();
  } else {
    glBindVertexArray(s.mesh_vao.id());
    glDrawElements(GL_TRIANGLES, s.index_count, GL_UNSIGNED_INT, nullptr);
  }
}

Result<LiveMesh> LiveVolume::read_mesh() const {
  const State& s = *state_;
  if (s.adaptive) {
    generate();
    return s.adaptive->read_back();
  }
  Result<std::vector<float>> positions = read_positions();
  if (!positions) return positions.error();
  LiveMesh m;
  m.mesh.positions = std::move(*positions);
  m.mesh.indices.resize(static_cast<std::size_t>(s.index_count));
  glBindBuffer(GL_COPY_READ_BUFFER, s.indices.id());
  glGetBufferSubData(GL_COPY_READ_BUFFER, 0,
                     static_cast<GLsizeiptr>(m.mesh.indices.size() * sizeof(std::uint32_t)),
                     m.mesh.indices.data());
  glBindBuffer(GL_COPY_READ_BUFFER, 0);
  if (std::string e = pending_error(); !e.empty())
    return Error{"OpenGL: reading the live volume's triangles: " + e};
  return m;
}

void LiveVolume::generate() const {
  const State& s = *state_;
  if (s.adaptive) {
    s.adaptive->generate([this](const Program& program) { bind(program, 2); });
    return;
  }
  s.target.bind();
  s.capture.use();
  static constexpr float kIdentity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  glUniformMatrix4fv(s.capture.uniform("view_projection"), 1, GL_TRUE, kIdentity);
  bind(s.capture, 2);
  glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 0, s.positions.id());
  glEnable(GL_RASTERIZER_DISCARD);
  glBeginTransformFeedback(GL_POINTS);
  glDrawArrays(GL_POINTS, 0, static_cast<GLsizei>(s.vertices));
  glEndTransformFeedback();
  glDisable(GL_RASTERIZER_DISCARD);
  glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 0, 0);
  glBindVertexArray(0);
}

Result<std::vector<float>> LiveVolume::read_positions() const {
  const State& s = *state_;
  if (s.adaptive) {
    Result<LiveMesh> m = read_mesh();
    if (!m) return m.error();
    return std::move(m->mesh.positions);
  }
  generate();
  std::vector<float> positions(3 * static_cast<std::size_t>(s.vertices));
  glBindBuffer(GL_COPY_READ_BUFFER, s.positions.id());
  glGetBufferSubData(GL_COPY_READ_BUFFER, 0,
                     static_cast<GLsizeiptr>(positions.size() * sizeof(float)), positions.data());
  glBindBuffer(GL_COPY_READ_BUFFER, 0);
  glUseProgram(0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (std::string e = pending_error(); !e.empty())
    return Error{"OpenGL: capturing the live volume's vertices: " + e};
  return positions;
}

}  // namespace lightvol
