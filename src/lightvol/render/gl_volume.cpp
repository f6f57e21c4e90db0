#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include <lightvol/core/check.h>
#include <lightvol/render/detail/airlight_glsl.h>
#include <lightvol/render/gl_density.h>
#include <lightvol/render/gl_volume.h>
#include <lightvol/render/live_volume.h>

namespace lightvol {

using namespace gl;

// ---- shared GLSL --------------------------------------------------------------------------------

// shaders/airlight.glsl, embedded at build time (cmake/embed_shader.cmake): the volume pass, the
// resolve pass and the functions they share, compiled one stage at a time by a #define.
namespace {
std::string stage_source(const char* stage, bool density = false) {
  return std::string("#version 450 core\n#define ") + stage + "\n" +
         (density ? "#define LIGHTVOL_DENSITY\n" : "") + detail::kAirlightGlsl;
}
const std::string kCommonSource = std::string("#define LIGHTVOL_COMMON\n") + detail::kAirlightGlsl;
}  // namespace

const char* const kGlslCommon = kCommonSource.c_str();

void set_scene_uniforms(const Program& program, const RenderScene& scene) {
  const Camera& cam = scene.camera;
  bool ok = false;
  const Mat4d inv_p = inverse(cam.view.projection, &ok);
  LV_CHECK(ok);
  const Mat4d inv_v = inverse(cam.view.view, &ok);
  LV_CHECK(ok);
  float m4[16], m3[9];
  for (int i = 0; i < 16; ++i) m4[i] = static_cast<float>(inv_p.m[i]);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m3[3 * r + c] = static_cast<float>(inv_v(r, c));
  auto f = [](double x) { return static_cast<float>(x); };
  const Vec3d origin = inv_v.transform_point({0, 0, 0});
  glUniformMatrix4fv(program.uniform("inv_projection"), 1, GL_TRUE, m4);
  glUniformMatrix3fv(program.uniform("eye_to_world"), 1, GL_TRUE, m3);
  glUniform3f(program.uniform("camera_position"), f(origin.x), f(origin.y), f(origin.z));
  glUniform1i(program.uniform("perspective"), cam.view.is_perspective() ? 1 : 0);
  glUniform2f(program.uniform("viewport"), f(cam.width), f(cam.height));
  glUniform1i(program.uniform("flip_y"), cam.view.flip_y ? 1 : 0);
  const Light& light = scene.light;
  glUniform1i(program.uniform("light_type"), light.type == LightType::directional ? 1 : 0);
  glUniform3f(program.uniform("light_position"), f(light.position.x), f(light.position.y),
              f(light.position.z));
  glUniform3f(program.uniform("light_direction"), f(light.direction.x), f(light.direction.y),
              f(light.direction.z));
  glUniform1f(program.uniform("light_near"), f(light.near));
  const Medium& m = scene.medium;
  glUniform1f(program.uniform("sigma_s"), f(m.scattering));
  glUniform1f(program.uniform("sigma_t"), f(m.extinction()));
  glUniform1f(program.uniform("intensity"), f(m.intensity));
  glUniform1i(program.uniform("phase_type"), static_cast<int>(m.phase.type));
  glUniform1f(program.uniform("phase_param"),
              f(m.phase.type == PhaseType::hg ? m.phase.g : m.phase.k));
  glUniform1f(program.uniform("f_u_max"), f(sun_table().u_max));
  const SpotProfile& profile = scene.medium.profile;
  const bool use_profile = profile.enabled() && light.type == LightType::spot;
  glUniform1i(program.uniform("profile_enabled"), use_profile ? 1 : 0);
  glUniform1f(program.uniform("profile_cos_inner"),
              f(std::cos(profile.inner_deg * std::numbers::pi / 180)));
  glUniform1f(program.uniform("profile_cos_outer"),
              f(std::cos(profile.outer_deg * std::numbers::pi / 180)));
}

// ---- the F(u, v) table --------------------------------------------------------------------------

const SunTable& sun_table() {
  static const SunTable table = [] {
    SunTable t;
    t.rows = 512;
    t.cols = 1024;
    t.u_max = 32;
    t.values.resize(static_cast<std::size_t>(t.rows) * t.cols);
    static constexpr double x[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267,
                                    0.9602898564975363};
    static constexpr double w[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745,
                                    0.1012285362903763};
    const double dv = 0.5 * std::numbers::pi / (t.cols - 1);
    for (int i = 0; i < t.rows; ++i) {
      const double a = static_cast<double>(i) / (t.rows - 1);
      const double u = t.u_max * a * a;
      double sum = 0;
      t.values[static_cast<std::size_t>(i) * t.cols] = 0;
      for (int j = 1; j < t.cols; ++j) {
        // ∫ over [v_{j−1}, v_j] of exp(−u tan ξ), two 8-point panels.
        const double lo = (j - 1) * dv;
        for (int p = 0; p < 2; ++p) {
          const double mid = lo + (p + 0.5) * 0.5 * dv, half = 0.25 * dv;
          for (int k = 0; k < 4; ++k)
            sum += half * w[k] *
                   (std::exp(-u * std::tan(mid - half * x[k])) +
                    std::exp(-u * std::tan(mid + half * x[k])));
        }
        t.values[static_cast<std::size_t>(i) * t.cols + j] = static_cast<float>(sum);
      }
    }
    return t;
  }();
  return table;
}

// ---- helpers ------------------------------------------------------------------------------------

TextureHandle make_surface_texture(const RenderScene& scene) {
  const int w = scene.camera.width, h = scene.camera.height;
  std::vector<float> rows(static_cast<std::size_t>(w) * h);
  for (int r = 0; r < h; ++r) {
    // GL row 0 is NDC y = −1: the image's last row, or its first for flip_y cameras.
    const int src = scene.camera.view.flip_y ? r : h - 1 - r;
    for (int c = 0; c < w; ++c) {
      const double t = scene.surface[static_cast<std::size_t>(src) * w + c];
      rows[static_cast<std::size_t>(r) * w + c] = std::isfinite(t) ? static_cast<float>(t) : 3e38f;
    }
  }
  return make_texture_2d(w, h, GL_R32F, rows.data(), 1);
}

Image image_from_gl(const RenderScene& scene, const std::vector<float>& top_first) {
  Image image;
  image.width = scene.camera.width;
  image.height = scene.camera.height;
  image.values.resize(top_first.size());
  const std::size_t w = static_cast<std::size_t>(image.width);
  for (int r = 0; r < image.height; ++r) {
    const int src = scene.camera.view.flip_y ? image.height - 1 - r : r;
    for (std::size_t c = 0; c < w; ++c) image.values[r * w + c] = top_first[src * w + c];
  }
  return image;
}

// ---- the renderer -------------------------------------------------------------------------------

namespace {}  // namespace

struct GlVolumeRenderer::State {
  RenderScene scene;
  GlVolumeOptions options;
  Program volume, resolve;
  Program live_program;              // compiled by the first set_volume(LiveVolume)
  const LiveVolume* live = nullptr;  // drawn instead of the mesh when set
  LiveDraw live_draw = LiveDraw::two_pass;
  Framebuffer accumulate, output;
  TextureHandle surface, table;
  GLuint external_surface = 0;  // set_surface's texture, or 0 for `surface`
  VertexArrayHandle vao, empty_vao;
  BufferHandle positions, indices;
  GLsizei index_count = 0;
  float view_projection[16] = {};
  float facing_sign = 1;
  std::unique_ptr<GlDensityGrid> grid;  // media of varying density
};

GlVolumeRenderer::~GlVolumeRenderer() = default;

Result<std::unique_ptr<GlVolumeRenderer>> GlVolumeRenderer::create(const RenderScene& scene,
                                                                   const GlVolumeOptions& options) {
  if (Status s = require_context(4, 5, false, "volume renderer"); !s) return s.error();
  std::unique_ptr<GlVolumeRenderer> r(new GlVolumeRenderer());
  r->state_ = std::make_unique<State>();
  State& s = *r->state_;
  s.scene = scene;
  s.options = options;
  const bool varying = scene.medium.density.varying();
  Result<Program> volume =
      Program::compile(stage_source("LIGHTVOL_VOLUME_VERTEX"),
                       stage_source("LIGHTVOL_VOLUME_FRAGMENT", varying), "volume");
  if (!volume) return volume.error();
  s.volume = std::move(*volume);
  Result<Program> resolve =
      Program::compile(stage_source("LIGHTVOL_RESOLVE_VERTEX"),
                       stage_source("LIGHTVOL_RESOLVE_FRAGMENT", varying), "resolve");
  if (!resolve) return resolve.error();
  s.resolve = std::move(*resolve);
  if (varying) {
    Result<std::unique_ptr<GlDensityGrid>> grid = GlDensityGrid::create(scene, options.density);
    if (!grid) return grid.error();
    s.grid = std::move(*grid);
  }
  const int w = scene.camera.width, h = scene.camera.height;
  Result<Framebuffer> acc = varying ? Framebuffer::create(w, h, {GL_RG32F, GL_R32F}, false)
                                    : Framebuffer::create(w, h, {GL_RG32F}, false);
  if (!acc) return acc.error();
  s.accumulate = std::move(*acc);
  Result<Framebuffer> out = Framebuffer::create(w, h, {GL_R32F}, false);
  if (!out) return out.error();
  s.output = std::move(*out);
  s.surface = make_surface_texture(scene);
  const SunTable& table = sun_table();
  s.table = make_texture_2d(table.cols, table.rows, GL_R32F, table.values.data(), 1);

  const Mat4d vp = scene.camera.view.projection * scene.camera.view.view;
  for (int i = 0; i < 16; ++i) s.view_projection[i] = static_cast<float>(vp.m[i]);
  // A mirroring camera turns GL's counter-clockwise front faces into back faces.
  const double det3 = vp(0, 0) * (vp(1, 1) * vp(2, 2) - vp(1, 2) * vp(2, 1)) -
                      vp(0, 1) * (vp(1, 0) * vp(2, 2) - vp(1, 2) * vp(2, 0)) +
                      vp(0, 2) * (vp(1, 0) * vp(2, 1) - vp(1, 1) * vp(2, 0));
  s.facing_sign = det3 < 0 ? 1.0f : -1.0f;

  GLuint id = 0;
  glGenVertexArrays(1, &id);
  s.vao = VertexArrayHandle(id);
  glGenVertexArrays(1, &id);
  s.empty_vao = VertexArrayHandle(id);
  glGenBuffers(1, &id);
  s.positions = BufferHandle(id);
  glGenBuffers(1, &id);
  s.indices = BufferHandle(id);
  glBindVertexArray(s.vao.id());
  glBindBuffer(GL_ARRAY_BUFFER, s.positions.id());
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  glEnableVertexAttribArray(0);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, s.indices.id());
  glBindVertexArray(0);

  for (const Program* p : {&s.volume, &s.resolve}) {
    p->use();
    set_scene_uniforms(*p, scene);
    glUniform1i(p->uniform("baseline"), options.baseline ? 1 : 0);
    glUniform1i(p->uniform("f_table"), 1);
  }
  s.volume.use();
  glUniform1i(s.volume.uniform("surface"), 0);
  // The profile's soft edge is only C1: more panels keep the quadrature at float accuracy.
  glUniform1i(s.volume.uniform("panels"),
              scene.medium.profile.enabled() ? std::max(options.panels, 8) : options.panels);
  glUniform1f(s.volume.uniform("facing_sign"), s.facing_sign);
  glUniformMatrix4fv(s.volume.uniform("view_projection"), 1, GL_TRUE, s.view_projection);
  s.resolve.use();
  glUniform1i(s.resolve.uniform("accumulated"), 0);
  glUniform1i(s.resolve.uniform("accumulated_density"), 2);
  glUseProgram(0);
  if (std::string e = pending_error(); !e.empty())
    return Error{"OpenGL: setting up the volume renderer: " + e};
  return r;
}

void GlVolumeRenderer::set_volume(const Mesh& volume) {
  State& s = *state_;
  glBindVertexArray(s.vao.id());
  glBindBuffer(GL_ARRAY_BUFFER, s.positions.id());
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(volume.positions.size() * sizeof(float)),
               volume.positions.data(), GL_STATIC_DRAW);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER,
               static_cast<GLsizeiptr>(volume.indices.size() * sizeof(std::uint32_t)),
               volume.indices.data(), GL_STATIC_DRAW);
  glBindVertexArray(0);
  s.index_count = static_cast<GLsizei>(volume.indices.size());
  s.live = nullptr;
}

Status GlVolumeRenderer::set_volume(const LiveVolume& live, LiveDraw draw) {
  State& s = *state_;
  if (live.adaptive() && draw == LiveDraw::vertex_stage)
    return Error{
        "live volume: an adaptive live volume is drawn in two passes (LiveDraw::two_pass)"};
  if (s.grid) return Error{"the live volume renders homogeneous media only"};
  if (s.live_program.id() == 0) {
    Result<Program> program =
        Program::compile(stage_source("LIGHTVOL_LIVE_VOLUME_VERTEX"),
                         stage_source("LIGHTVOL_VOLUME_FRAGMENT"), "live volume");
    if (!program) return program.error();
    s.live_program = std::move(*program);
    const Program& p = s.live_program;
    p.use();
    set_scene_uniforms(p, s.scene);
    glUniform1i(p.uniform("baseline"), s.options.baseline ? 1 : 0);
    glUniform1i(p.uniform("f_table"), 1);
    glUniform1i(p.uniform("surface"), 0);
    glUniform1i(p.uniform("panels"), s.scene.medium.profile.enabled()
                                         ? std::max(s.options.panels, 8)
                                         : s.options.panels);
    glUniform1f(p.uniform("facing_sign"), s.facing_sign);
    glUniformMatrix4fv(p.uniform("view_projection"), 1, GL_TRUE, s.view_projection);
    glUseProgram(0);
    if (std::string e = pending_error(); !e.empty())
      return Error{"OpenGL: setting up the live volume's program: " + e};
  }
  s.live = &live;
  s.live_draw = draw;
  return {};
}

Status GlVolumeRenderer::set_surface(GLuint texture) {
  State& s = *state_;
  if (texture == 0) {
    s.external_surface = 0;
    return {};
  }
  const std::string name = "surface texture " + std::to_string(texture);
  (void)pending_error();
  if (glIsTexture(texture) != GL_TRUE) return Error{name + ": not a texture name"};
  glBindTexture(GL_TEXTURE_2D, texture);
  if (!pending_error().empty()) return Error{name + ": not a 2D texture"};
  GLint w = 0, h = 0, format = 0;
  glGetTexLevelParameteriv(GL_TEXTURE_2D, 0, GL_TEXTURE_WIDTH, &w);
  glGetTexLevelParameteriv(GL_TEXTURE_2D, 0, GL_TEXTURE_HEIGHT, &h);
  glGetTexLevelParameteriv(GL_TEXTURE_2D, 0, GL_TEXTURE_INTERNAL_FORMAT, &format);
  glBindTexture(GL_TEXTURE_2D, 0);
  if (w != s.scene.camera.width || h != s.scene.camera.height)
    return Error{name + ": level 0 is " + std::to_string(w) + "x" + std::to_string(h) +
                 ", the camera " + std::to_string(s.scene.camera.width) + "x" +
                 std::to_string(s.scene.camera.height)};
  if (format != GL_R32F) {
    char hex[16];
    std::snprintf(hex, sizeof hex, "0x%04X", static_cast<unsigned>(format));
    return Error{name + ": internal format " + hex + " is not GL_R32F"};
  }
  s.external_surface = texture;
  return {};
}

Image GlVolumeRenderer::render(double* seconds) {
  State& s = *state_;
  const auto start = std::chrono::steady_clock::now();
  const bool in_vertex_stage = s.live && s.live_draw == LiveDraw::vertex_stage;
  if (s.live && !in_vertex_stage) s.live->generate();  // the live volume's vertices, once each
  if (s.grid) s.grid->update();  // the opacity map and the in-scattering grid of this frame
  // Pass 1: every fragment of the volume, additive, no depth test, no clipping in depth.
  s.accumulate.bind();
  glClearColor(0, 0, 0, 0);
  glClear(GL_COLOR_BUFFER_BIT);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glEnable(GL_DEPTH_CLAMP);
  glEnable(GL_BLEND);
  glBlendEquation(GL_FUNC_ADD);
  glBlendFunc(GL_ONE, GL_ONE);
  // A live volume drawn in the vertex stage makes its vertices here, from its shadow maps (texture
  // units 2 to 7); a mesh's, or a generated live volume's, come from their buffers.
  const Program& program = in_vertex_stage ? s.live_program : s.volume;
  program.use();
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, s.external_surface != 0 ? s.external_surface : s.surface.id());
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_2D, s.table.id());
  if (s.grid) s.grid->bind(program);
  if (in_vertex_stage) {
    s.live->bind(program, 2);
    glDrawElements(GL_TRIANGLES, s.live->index_count(), GL_UNSIGNED_INT, nullptr);
  } else if (s.live) {
    s.live->draw_mesh();
  } else {
    glBindVertexArray(s.vao.id());
    glDrawElements(GL_TRIANGLES, s.index_count, GL_UNSIGNED_INT, nullptr);
  }
  glDisable(GL_BLEND);
  glDisable(GL_DEPTH_CLAMP);
  // Pass 2: per-pixel constants and the baseline.
  s.output.bind();
  s.resolve.use();
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, s.accumulate.color_texture(0));
  if (s.grid) {
    glActiveTexture(GL_TEXTURE2);
    glBindTexture(GL_TEXTURE_2D, s.accumulate.color_texture(1));
    glActiveTexture(GL_TEXTURE0);
  }
  glBindVertexArray(s.empty_vao.id());
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glFinish();
  if (seconds)
    *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  glBindVertexArray(0);
  glUseProgram(0);
  const Image image = image_from_gl(s.scene, s.output.read(0, 1));
  LV_CHECK_EQ(pending_error(), std::string());
  return image;
}

}  // namespace lightvol
