#include <algorithm>
#include <chrono>
#include <cstring>
#include <memory>
#include <string>
#include <utility>

#include <lightvol/core/check.h>
#include <lightvol/scene/shadowmap.h>

namespace lightvol {

using namespace lightvol::gl;

namespace {

constexpr const char* kVertexShader = R"(#version 450 core
layout(location = 0) in vec3 position;
uniform mat4 mvp_hi;  // world -> clip, split into a float pair: (double) hi + lo
uniform mat4 mvp_lo;
void main() {
  dmat4 m = dmat4(mvp_hi) + dmat4(mvp_lo);
  gl_Position = vec4(m * dvec4(dvec3(position), 1.0lf));
}
)";

constexpr const char* kFragmentShader = R"(#version 450 core
void main() {}
)";

// Uploads a row-major double matrix as two column-major float matrices whose sum is it to ~48 bits.
void set_matrix(const Program& program, const Mat4d& m) {
  float hi[16], lo[16];
  for (int i = 0; i < 16; ++i) {
    hi[i] = static_cast<float>(m.m[i]);
    lo[i] = static_cast<float>(m.m[i] - static_cast<double>(hi[i]));
  }
  glUniformMatrix4fv(program.uniform("mvp_hi"), 1, GL_TRUE, hi);
  glUniformMatrix4fv(program.uniform("mvp_lo"), 1, GL_TRUE, lo);
}

}  // namespace

Result<ShadowMapRenderer> ShadowMapRenderer::create(const Mesh& scene) {
  if (Status s = require_context(4, 5, false, "shadow-map depth pass"); !s) return s.error();
  ShadowMapRenderer r;
  Result<Program> program =
      Program::compile(kVertexShader, kFragmentShader, "shadow-map depth pass");
  if (!program) return program.error();
  r.program_ = std::move(*program);

  GLuint id = 0;
  glGenVertexArrays(1, &id);
  r.vao_ = VertexArrayHandle(id);
  glBindVertexArray(id);
  glGenBuffers(1, &id);
  r.vertices_ = BufferHandle(id);
  glBindBuffer(GL_ARRAY_BUFFER, id);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(scene.positions.size() * sizeof(float)),
               scene.positions.data(), GL_STATIC_DRAW);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 3 * sizeof(float), nullptr);
  glEnableVertexAttribArray(0);
  glGenBuffers(1, &id);
  r.indices_ = BufferHandle(id);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, id);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER,
               static_cast<GLsizeiptr>(scene.indices.size() * sizeof(std::uint32_t)),
               scene.indices.data(), GL_STATIC_DRAW);
  glBindVertexArray(0);
  r.num_indices_ = scene.indices.size();
  if (const std::string e = pending_error(); !e.empty())
    return Error{"OpenGL: uploading the scene (" + std::to_string(scene.num_triangles()) +
                 " triangles): " + e};
  return r;
}

Result<std::vector<float>> ShadowMapRenderer::render_window_depth(const Light& light, int width,
                                                                  int height, int face,
                                                                  double* gpu_seconds) const {
  LV_CHECK(width > 0 && height > 0);
  Result<Framebuffer> fbo = Framebuffer::create(width, height, {}, /*with_depth=*/true);
  if (!fbo) return fbo.error();
  fbo->bind();
  // Wall-clock time of the GPU work (draw + glFinish): llvmpipe's GL_TIME_ELAPSED is unreliable.
  const auto start = std::chrono::steady_clock::now();
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glClearDepth(1.0);
  glClear(GL_DEPTH_BUFFER_BIT);
  program_.use();
  set_matrix(program_, light.projection * pass_view(light, face));
  glBindVertexArray(vao_.id());
  glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(num_indices_), GL_UNSIGNED_INT, nullptr);
  glBindVertexArray(0);
  glFinish();
  if (gpu_seconds)
    *gpu_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::vector<float> depth = fbo->read(-1, 1);  // first row = top (NDC y = +1)
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (const std::string e = pending_error(); !e.empty())
    return Error{"OpenGL: depth pass " + std::to_string(width) + "x" + std::to_string(height) +
                 ": " + e};
  if (light.flip_y) {
    const std::size_t w = static_cast<std::size_t>(width);
    for (std::size_t top = 0, bottom = static_cast<std::size_t>(height) - 1; top < bottom;
         ++top, --bottom)
      std::swap_ranges(depth.begin() + static_cast<std::ptrdiff_t>(top * w),
                       depth.begin() + static_cast<std::ptrdiff_t>((top + 1) * w),
                       depth.begin() + static_cast<std::ptrdiff_t>(bottom * w));
  }
  return depth;
}

void ShadowMapRenderer::draw(const Light& light, int face, const Mat4d& model) const {
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  program_.use();
  set_matrix(program_, light.projection * pass_view(light, face) * model);
  glBindVertexArray(vao_.id());
  glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(num_indices_), GL_UNSIGNED_INT, nullptr);
  glBindVertexArray(0);
  glUseProgram(0);
}

Result<std::vector<DepthImage>> ShadowMapRenderer::render(const Light& light, MapSize size,
                                                          double* gpu_seconds) const {
  std::vector<DepthImage> images;
  double total = 0;
  for (int face = 0; face < pass_count(light); ++face) {
    double seconds = 0;
    Result<std::vector<float>> window =
        render_window_depth(light, size.width, size.height, face, &seconds);
    if (!window) return window.error();
    total += seconds;
    images.push_back(encode_depth(light, size.width, size.height, *window));
  }
  if (gpu_seconds) *gpu_seconds = total;
  return images;
}

namespace {

class GlDepthPasses final : public DepthPasses {
 public:
  GlDepthPasses(std::unique_ptr<Context> context, ShadowMapRenderer renderer)
      : context_(std::move(context)), renderer_(std::move(renderer)) {}

  std::string method() const override { return "OpenGL"; }

  Result<std::vector<float>> window_depth(const Light& view, int width, int height, int face,
                                          double* gpu_seconds) override {
    return renderer_.render_window_depth(view, width, height, face, gpu_seconds);
  }

 private:
  std::unique_ptr<Context> context_;  // declared first: destroyed after the renderer
  ShadowMapRenderer renderer_;
};

}  // namespace

Result<std::unique_ptr<DepthPasses>> gl_depth_passes(const Mesh& scene, const std::string& source) {
  Result<std::unique_ptr<Context>> context = Context::create();
  if (!context) return context.error();
  Result<ShadowMapRenderer> renderer = ShadowMapRenderer::create(scene);
  if (!renderer) return Error{source + ": " + renderer.error().message};
  return std::unique_ptr<DepthPasses>(
      std::make_unique<GlDepthPasses>(std::move(*context), std::move(*renderer)));
}

}  // namespace lightvol
