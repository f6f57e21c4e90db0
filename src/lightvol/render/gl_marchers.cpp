#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include <lightvol/core/check.h>
#include <lightvol/gl/context.h>
#include <lightvol/render/gl_density.h>
#include <lightvol/render/gl_marchers.h>
#include <lightvol/render/gl_volume.h>

namespace lightvol {

using namespace gl;

std::vector<float> window_depth_maps(const Light& light, const std::vector<DepthImage>& maps) {
  std::vector<float> out;
  for (std::size_t f = 0; f < maps.size(); ++f) {
    const DepthImage& map = maps[f];
    const Unprojector un(light, map.width, map.height, static_cast<int>(f), Space::world);
    const Mat4d view =
        light.type == LightType::omni ? omni_face_view(light, static_cast<int>(f)) : light.view;
    const Mat4d to_clip = light.projection * view;
    for (int row = 0; row < map.height; ++row)
      for (int col = 0; col < map.width; ++col) {
        Vec3d p;
        double window = 1.0;
        if (un.point(col, row, map.at(col, row), &p))
          window = 0.5 * to_clip.transform_point(p).z + 0.5;
        out.push_back(static_cast<float>(std::clamp(window, 0.0, 1.0)));
      }
  }
  return out;
}

namespace {

const char* const kFullscreenVs = R"(#version 450 core
void main() {
  vec2 p = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0);
  gl_Position = vec4(p, 0.0, 1.0);
}
)";

const char* const kMarchFs = R"(
layout(location = 0) out float result;
uniform sampler2D surface;
uniform sampler2D shadow;      // window depth, faces stacked, first stored row at t = 0
uniform ivec2 map_size;        // one face
uniform int faces;             // 1 or 6
uniform int map_flip_y;
uniform mat4 light_views[6];   // world -> light (face) eye
uniform mat4 light_projection;
uniform mat4 bounds_view;      // world -> the frame of the bounds box
uniform vec3 bounds_lo;
uniform vec3 bounds_hi;
uniform int samples;
uniform int interleave;

float stored(int face, int col, int row) {
  return texelFetch(shadow, ivec2(col, face * map_size.y + row), 0).r;
}

bool lit(vec3 x) {
  int face = 0;
  if (faces == 6) {
    vec3 d = x - light_position;
    vec3 a = abs(d);
    if (a.x >= a.y && a.x >= a.z) face = d.x > 0.0 ? 0 : 1;
    else if (a.y >= a.z) face = d.y > 0.0 ? 2 : 3;
    else face = d.z > 0.0 ? 4 : 5;
  }
  vec4 e = light_views[face] * vec4(x, 1.0);
  vec4 c = light_projection * e;
  if (c.w <= 0.0) return false;
  vec3 ndc = c.xyz / c.w;
  if (ndc.z > 1.0) return false;
  float fc = (ndc.x + 1.0) * 0.5 * float(map_size.x) - 0.5;
  float y = map_flip_y == 1 ? ndc.y : -ndc.y;
  float fr = (y + 1.0) * 0.5 * float(map_size.y) - 0.5;
  vec2 hi = vec2(map_size - 1);
  if (faces == 6) {
    fc = clamp(fc, 0.0, hi.x);
    fr = clamp(fr, 0.0, hi.y);
  } else if (fc < 0.0 || fr < 0.0 || fc > hi.x || fr > hi.y) {
    return false;
  }
  int i = min(int(fc), map_size.x - 2), j = min(int(fr), map_size.y - 2);
  float fx = fc - float(i), fy = fr - float(j);
  // The static volume's triangles (a, b, c) and (b, d, c) of the texel quad.
  float a = stored(face, i, j), b = stored(face, i + 1, j);
  float cc = stored(face, i, j + 1), d = stored(face, i + 1, j + 1);
  float depth = fx + fy <= 1.0 ? a + fx * (b - a) + fy * (cc - a)
                               : d + (1.0 - fx) * (cc - d) + (1.0 - fy) * (b - d);
  return 0.5 * ndc.z + 0.5 <= depth;
}

void main() {
  vec3 origin, dir;
  pixel_ray(origin, dir);
  float t_surface = texelFetch(surface, ivec2(gl_FragCoord.xy), 0).r;
  // The ray's span inside the light's bounds.
  vec3 o = (bounds_view * vec4(origin, 1.0)).xyz;
  vec3 dv = mat3(bounds_view) * dir;
  vec3 inv = 1.0 / dv;
  vec3 ta = (bounds_lo - o) * inv, tb = (bounds_hi - o) * inv;
  vec3 tmin = min(ta, tb), tmax = max(ta, tb);
  float t0 = max(max(tmin.x, tmin.y), max(tmin.z, 0.0));
  float t1 = min(min(tmax.x, tmax.y), min(tmax.z, t_surface));
  result = 0.0;
  if (!(t1 > t0)) return;
  ivec2 p = ivec2(gl_FragCoord.xy) % interleave;
  float offset = (float(p.x + interleave * p.y) + 0.5) / float(interleave * interleave);
  float dt = (t1 - t0) / float(samples);
  float sum = 0.0;
#ifdef LIGHTVOL_DENSITY
  // The eye-side optical depth up to the bounds (a quarter as many midpoint steps), then along.
  float tau_e = 0.0;
  int before = max(samples / 4, 8);
  for (int k = 0; k < before; ++k)
    tau_e += sigma_t * density(origin + ((float(k) + 0.5) * t0 / float(before)) * dir);
  tau_e *= t0 / float(before);
#endif
  for (int k = 0; k < samples; ++k) {
    float t = t0 + (float(k) + offset) * dt;
    vec3 x = origin + t * dir;
#ifdef LIGHTVOL_DENSITY
    float rho = density(x);
    float te = tau_e + sigma_t * rho * offset * dt;
    tau_e += sigma_t * rho * dt;
    if (!lit(x)) continue;
    float light_part;
    if (light_type == 1) {
      light_part = phase(-dot(dir, light_direction));
    } else {
      vec3 to_x = x - light_position;
      float dist = length(to_x);
      light_part = phase(dot(to_x / dist, -dir)) / (dist * dist) * profile(to_x);
    }
    sum += light_part * rho * exp(-light_optical_depth(x) - te);
    continue;
#endif
    if (!lit(x)) continue;
    float radiance;
    if (light_type == 1) {
      float z = dot(x - light_position, light_direction) - light_near;
      radiance = phase(-dot(dir, light_direction)) * exp(-sigma_t * z);
    } else {
      vec3 to_x = x - light_position;
      float dist = length(to_x);
      radiance = phase(dot(to_x / dist, -dir)) * exp(-sigma_t * dist) / (dist * dist) * profile(to_x);
    }
    sum += radiance * exp(-sigma_t * t);
  }
  result = sigma_s * intensity * sum * dt;
}
)";

// One direction of the separable M-wide box gather.
const char* const kGatherFs = R"(#version 450 core
layout(location = 0) out float result;
uniform sampler2D source;
uniform ivec2 step_dir;
uniform int width;
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  ivec2 size = textureSize(source, 0);
  float sum = 0.0;
  int n = 0;
  for (int k = -(width - 1) / 2; k <= width / 2; ++k) {
    ivec2 q = p + k * step_dir;
    if (q.x < 0 || q.y < 0 || q.x >= size.x || q.y >= size.y) continue;
    sum += texelFetch(source, q, 0).r;
    ++n;
  }
  result = sum / float(max(n, 1));
}
)";

const char* const kOcclusionFs = R"(
layout(location = 0) out float result;
uniform sampler2D surface;
void main() {
  vec3 origin, dir;
  pixel_ray(origin, dir);
  vec3 to_light = light_position - origin;
  float t_surface = texelFetch(surface, ivec2(gl_FragCoord.xy), 0).r;
  // Unoccluded where the visible surface lies beyond the light. The glow is the unshadowed
  // in-scattering around the light, ∝ p(θ)·e^(−σt·D)/h (h: distance of the light from the ray).
  float h, s0;
  point_setup(origin, dir, h, s0);
  float dist = length(to_light);
  float glow = sigma_s * intensity * phase(dot(dir, to_light / dist)) * exp(-sigma_t * dist) /
               max(h, 0.02 * dist);
  result = t_surface > dist ? glow : 0.0;
}
)";

const char* const kRadialFs = R"(#version 450 core
layout(location = 0) out float result;
uniform sampler2D occlusion;
uniform vec2 light_uv;
uniform int samples;
uniform float exposure;
uniform float weight;
uniform float decay;
uniform float density;
void main() {
  vec2 size = vec2(textureSize(occlusion, 0));
  vec2 uv = gl_FragCoord.xy / size;
  vec2 delta = (uv - light_uv) * density / float(samples);
  float illumination_decay = 1.0;
  float sum = 0.0;
  for (int i = 0; i < samples; ++i) {
    uv -= delta;
    ivec2 q = clamp(ivec2(uv * size), ivec2(0), ivec2(size) - 1);
    sum += texelFetch(occlusion, q, 0).r * illumination_decay * weight;
    illumination_decay *= decay;
  }
  result = sum * exposure;
}
)";

std::string with_common(const char* body, bool density = false) {
  if (density)
    return std::string("#version 450 core\n#define LIGHTVOL_DENSITY\n") + kGlslCommon +
           kGlslDensity + kGlslOpacityLookup + body;
  return std::string("#version 450 core\n") + kGlslCommon + body;
}

void set_matrix(const Program& p, const char* name, const Mat4d& m) {
  float v[16];
  for (int i = 0; i < 16; ++i) v[i] = static_cast<float>(m.m[i]);
  glUniformMatrix4fv(p.uniform(name), 1, GL_TRUE, v);
}

}  // namespace

struct GlMarcher::State {
  RenderScene scene;
  MarchOptions options;
  Program first, gather, radial;
  Framebuffer a, b;
  TextureHandle surface, shadow;
  VertexArrayHandle vao;
  bool light_behind = false;
  std::unique_ptr<GlOpacityMap> opacity;  // media of varying density
  std::shared_ptr<const GlDensityField> field;
};

GlMarcher::~GlMarcher() = default;

// Long (over 80 lines) on purpose: it checks the inputs, then compiles the marcher's programs and
// sets their textures and uniforms in the order GL needs them; a straight sequence.
Result<std::unique_ptr<GlMarcher>> GlMarcher::create(const RenderScene& scene,
                                                     const std::vector<DepthImage>& maps,
                                                     const std::vector<std::string>& sources,
                                                     const MarchOptions& options) {
  if (Status s = require_context(4, 5, false, "ray marcher"); !s) return s.error();
  LV_CHECK_EQ(maps.size(), sources.size());
  const Light& light = scene.light;
  const std::size_t want = light.type == LightType::omni ? 6 : 1;
  if (options.method == MarchMethod::raymarch && maps.size() != want)
    return Error{"raymarch: a " + std::string(to_string(light.type)) + " light takes " +
                 std::to_string(want) + " shadow map(s), got " + std::to_string(maps.size())};
  for (std::size_t f = 1; f < maps.size(); ++f)
    if (maps[f].width != maps[0].width || maps[f].height != maps[0].height)
      return Error{sources[f] + ": shadow map face is " + std::to_string(maps[f].width) + "x" +
                   std::to_string(maps[f].height) + ", the first is " +
                   std::to_string(maps[0].width) + "x" + std::to_string(maps[0].height)};
  if (options.samples < 1 || options.interleave < 1)
    return Error{"raymarch: samples and interleave must be >= 1"};

  std::unique_ptr<GlMarcher> r(new GlMarcher());
  r->state_ = std::make_unique<State>();
  State& s = *r->state_;
  s.scene = scene;
  s.options = options;
  const bool march = options.method == MarchMethod::raymarch;
  const bool varying = march && scene.medium.density.varying();
  if (scene.medium.density.varying() && !march)
    return Error{"radial: renders homogeneous media only"};
  Result<Program> first =
      Program::compile(kFullscreenVs, with_common(march ? kMarchFs : kOcclusionFs, varying),
                       march ? "raymarch" : "radial occlusion");
  if (!first) return first.error();
  s.first = std::move(*first);
  Result<Program> second = Program::compile(kFullscreenVs, march ? kGatherFs : kRadialFs,
                                            march ? "gather" : "radial blur");
  if (!second) return second.error();
  (march ? s.gather : s.radial) = std::move(*second);
  const int w = scene.camera.width, h = scene.camera.height;
  for (Framebuffer* fb : {&s.a, &s.b}) {
    Result<Framebuffer> made = Framebuffer::create(w, h, {GL_R32F}, false);
    if (!made) return made.error();
    *fb = std::move(*made);
  }
  s.surface = make_surface_texture(scene);
  GLuint vao = 0;
  glGenVertexArrays(1, &vao);
  s.vao = VertexArrayHandle(vao);

  s.first.use();
  set_scene_uniforms(s.first, scene);
  glUniform1i(s.first.uniform("surface"), 0);
  if (march) {
    const std::vector<float> window = window_depth_maps(light, maps);
    s.shadow = make_texture_2d(maps[0].width, maps[0].height * static_cast<int>(maps.size()),
                               GL_R32F, window.data(), 1);
    glUniform1i(s.first.uniform("shadow"), 1);
    glUniform2i(s.first.uniform("map_size"), maps[0].width, maps[0].height);
    glUniform1i(s.first.uniform("faces"), static_cast<int>(maps.size()));
    glUniform1i(s.first.uniform("map_flip_y"), light.flip_y ? 1 : 0);
    for (std::size_t f = 0; f < maps.size(); ++f) {
      const std::string name = "light_views[" + std::to_string(f) + "]";
      set_matrix(
          s.first, name.c_str(),
          light.type == LightType::omni ? omni_face_view(light, static_cast<int>(f)) : light.view);
    }
    set_matrix(s.first, "light_projection", light.projection);
    // Bounds: omni, a cube of half-size `far` around the light; else the frustum's box in eye
    // space.
    const auto [lo, hi] = light_eye_box(light);
    set_matrix(s.first, "bounds_view", light.view);
    glUniform3f(s.first.uniform("bounds_lo"), float(lo.x), float(lo.y), float(lo.z));
    glUniform3f(s.first.uniform("bounds_hi"), float(hi.x), float(hi.y), float(hi.z));
    glUniform1i(s.first.uniform("samples"), options.samples);
    glUniform1i(s.first.uniform("interleave"), options.interleave);
    if (varying) {
      Result<std::shared_ptr<const GlDensityField>> field =
          GlDensityField::create(scene.medium.density);
      if (!field) return field.error();
      s.field = *field;
      Result<std::unique_ptr<GlOpacityMap>> opacity =
          GlOpacityMap::create(light, scene.medium, options.opacity, light_reach(scene), s.field);
      if (!opacity) return opacity.error();
      s.opacity = std::move(*opacity);
      s.first.use();
      s.field->bind(s.first);
      s.opacity->bind(s.first);
    }
    s.gather.use();
    glUniform1i(s.gather.uniform("source"), 0);
    glUniform1i(s.gather.uniform("width"), options.interleave);
  } else {
    const Mat4d vp = scene.camera.view.projection * scene.camera.view.view;
    const Vec3d eye_l = scene.camera.view.view.transform_point(light.position);
    s.light_behind = eye_l.z >= 0;
    const Vec3d ndc = vp.transform_point(light.position);
    double y = scene.camera.view.flip_y ? -ndc.y : ndc.y;
    s.radial.use();
    glUniform1i(s.radial.uniform("occlusion"), 0);
    glUniform2f(s.radial.uniform("light_uv"), float(0.5 * ndc.x + 0.5), float(0.5 * y + 0.5));
    glUniform1i(s.radial.uniform("samples"), options.samples);
    glUniform1f(s.radial.uniform("exposure"), float(options.exposure));
    glUniform1f(s.radial.uniform("weight"),
                float(options.weight > 0 ? options.weight : 1.0 / options.samples));
    glUniform1f(s.radial.uniform("decay"), float(options.decay));
    glUniform1f(s.radial.uniform("density"), float(options.density));
  }
  glUseProgram(0);
  if (std::string e = pending_error(); !e.empty())
    return Error{"OpenGL: setting up the marcher: " + e};
  return r;
}

Image GlMarcher::render(double* seconds) {
  State& s = *state_;
  const auto start = std::chrono::steady_clock::now();
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  if (s.opacity) s.opacity->update();  // this frame's light-side optical depths
  glBindVertexArray(s.vao.id());
  // Pass 1: march (or the occlusion pre-pass) into a.
  s.a.bind();
  s.first.use();
  if (s.opacity) s.opacity->bind(s.first);
  if (s.field) s.field->bind_texture();
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, s.surface.id());
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_2D, s.shadow.id());
  glDrawArrays(GL_TRIANGLES, 0, 3);
  const Framebuffer* result = &s.a;
  glActiveTexture(GL_TEXTURE0);
  if (s.options.method == MarchMethod::raymarch) {
    if (s.options.interleave > 1) {
      s.gather.use();
      s.b.bind();
      glBindTexture(GL_TEXTURE_2D, s.a.color_texture(0));
      glUniform2i(s.gather.uniform("step_dir"), 1, 0);
      glDrawArrays(GL_TRIANGLES, 0, 3);
      s.a.bind();
      glBindTexture(GL_TEXTURE_2D, s.b.color_texture(0));
      glUniform2i(s.gather.uniform("step_dir"), 0, 1);
      glDrawArrays(GL_TRIANGLES, 0, 3);
    }
  } else {
    s.b.bind();
    if (s.light_behind) {
      glClearColor(0, 0, 0, 0);
      glClear(GL_COLOR_BUFFER_BIT);
    } else {
      s.radial.use();
      glBindTexture(GL_TEXTURE_2D, s.a.color_texture(0));
      glDrawArrays(GL_TRIANGLES, 0, 3);
    }
    result = &s.b;
  }
  glFinish();
  if (seconds)
    *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  glBindVertexArray(0);
  glUseProgram(0);
  const Image image = image_from_gl(s.scene, result->read(0, 1));
  LV_CHECK_EQ(pending_error(), std::string());
  return image;
}

}  // namespace lightvol
