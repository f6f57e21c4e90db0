// The OpenGL depth pass of `lightvol shadowmap`: a scene mesh rendered headless from a light (or a
// camera) into a GL_DEPTH_COMPONENT32F buffer, read back as float window depth.
//
// OpenGL's default conventions throughout: clip z in [−w, w], glDepthRange(0, 1), depth sampled at
// pixel centres, GL_LESS against a buffer cleared to 1, no culling (a shadow map sees both sides of
// every triangle). The vertex shader transforms in double precision (the light's matrix is passed
// as a float pair hi + lo), so the result agrees with exact ray casting (scene/raycast.h) to the
// float rounding of the clip coordinates and of the stored depth, except at silhouette texels
// where a triangle edge passes within rounding of the texel centre.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/gl/context.h>
#include <lightvol/light/light.h>
#include <lightvol/scene/depth_passes.h>
#include <lightvol/scene/scene.h>

namespace lightvol {

class ShadowMapRenderer {
 public:
  // Uploads the scene's triangles. A gl::Context must be current on this thread and outlive the
  // renderer. Errors: the shader does not compile, or the driver runs out of memory.
  static Result<ShadowMapRenderer> create(const Mesh& scene);

  // Window depth of one W×H pass of `light` (omni: face `face`), row-major as stored: first row =
  // top of the view (NDC y = +1) unless the light's flip_y. 1 where nothing was hit. When
  // `gpu_seconds` is given, it receives the wall-clock time of the GPU work (clear, triangles,
  // glFinish; not the read-back).
  Result<std::vector<float>> render_window_depth(const Light& light, int width, int height,
                                                 int face, double* gpu_seconds = nullptr) const;

  // Every pass of the light (one, or six omni faces +X −X +Y −Y +Z −Z), each `size`, in the
  // light's depth encoding (encode_depth). `gpu_seconds` receives the sum over the passes.
  Result<std::vector<DepthImage>> render(const Light& light, MapSize size,
                                         double* gpu_seconds = nullptr) const;

  // The depth pass into a texture that stays on the GPU (a live volume's shadow map, an engine's
  // frame): draws the scene's triangles, moved by `model` (world ← scene), as pass `face` of
  // `light` sees them, into the bound framebuffer's depth buffer with the state of
  // render_window_depth (depth test GL_LESS, depth writes on, no culling, no blending); it
  // neither clears nor reads back. Several renderers (a static scene and moving objects) draw
  // into one pass between the caller's glClear(GL_DEPTH_BUFFER_BIT) and its use. No allocation.
  void draw(const Light& light, int face, const Mat4d& model = Mat4d::identity()) const;

  std::size_t num_triangles() const { return num_indices_ / 3; }

 private:
  ShadowMapRenderer() = default;
  gl::Program program_;
  gl::VertexArrayHandle vao_;
  gl::BufferHandle vertices_, indices_;
  std::size_t num_indices_ = 0;
};

// Depth passes on the GPU: creates a headless gl::Context (made current on this thread, and kept
// current for the object's lifetime: other GL renderers may use it meanwhile) and a
// ShadowMapRenderer of `scene`. Errors: no OpenGL context (the context's message), or the scene
// does not upload (named by `source`).
Result<std::unique_ptr<DepthPasses>> gl_depth_passes(const Mesh& scene, const std::string& source);

}  // namespace lightvol
