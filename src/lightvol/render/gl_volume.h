// The paper's method on the GPU: a light volume rasterized with additive float blending, each
// fragment adding or subtracting the airlight from the eye to it (docs/design.md §6, method
// `volume`).
//
// Float precision. A fragment's La(0, t) can be much larger than the pixel's net airlight (the
// differences of large values the paper warns about). The renderer therefore
//   1. factors out the per-pixel constant C = 2σs·I·e^(−σt·s0)/h of the point-light integral, so
//      fragments accumulate only the angular integral ∫ p(cos 2ξ) e^(−u tan ξ) dξ (≤ π/4·max p);
//   2. integrates each fragment from the ray's point closest to the light (ξ = π/4, s = s0) rather
//      than from the eye (ξ0 = γ/2), and counts the fragments' signs in a second channel n;
//   3. resolves per pixel: La = C·(R + n·∫ from ξ0 to π/4), which is exact for any fragment count
//      (camera inside or outside the volume, near-plane clipping).
// The values summed in float are then bounded by the part of the integral on one side of the
// closest point, not by the whole airlight from the eye. `baseline = false` switches 2–3 off
// (fragments integrate from the eye) to measure what it buys. Directional lights need no baseline:
// their fragments add (1 − e^(−σt(1+k)t)) / (σt(1+k)) and the resolve multiplies by the rest.
//
// Isotropic media read Sun et al.'s F(u, v) from a 2D float texture (u = σt·h on a square-root axis
// up to u_max = 32, v on [0, π/2]; bilinear interpolation in the shader with float weights);
// Henyey–Greenstein and Schlick phases, u beyond the table, and spot lights with a soft-edged
// profile (Medium::profile, docs/design.md §6) use 8-point Gauss–Legendre panels (8 per fragment
// with a profile, whose smoothstep edge is only C¹). Fragments beyond the visible surface clamp
// their t to the camera depth (a texture); depth test and clipping are off (GL_DEPTH_CLAMP) so no
// fragment of the closed volume is lost.
#pragma once

#include <memory>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>
#include <lightvol/gl/context.h>
#include <lightvol/render/gl_density.h>
#include <lightvol/render/scene.h>

namespace lightvol {

class LiveVolume;

// How a live volume is drawn: its vertices first made once each into a vertex buffer by transform
// feedback and then drawn from it as a mesh is (two passes: the default, the faster on llvmpipe,
// docs/performance.md), or made by the volume pass's own vertex stage for every index drawn (one
// pass: the paper's displaced grid).
enum class LiveDraw { two_pass, vertex_stage };

struct GlVolumeOptions {
  bool baseline = true;  // integrate fragments from the closest point to the light (see above)
  int panels = 2;  // Gauss–Legendre panels (8 nodes each) per fragment for quadrature phases
  // Media of varying density: the per-frame in-scattering grid and opacity map (gl_density.h).
  DensityGridOptions density;
};

// Renders light volumes of one scene. Needs a current gl::Context on this thread for its lifetime.
class GlVolumeRenderer {
 public:
  // Compiles the programs and uploads the scene (surface distances, F table). Errors: a shader
  // that does not compile (a driver problem), an incomplete framebuffer.
  static Result<std::unique_ptr<GlVolumeRenderer>> create(const RenderScene& scene,
                                                          const GlVolumeOptions& options = {});
  ~GlVolumeRenderer();

  // Uploads the volume (world space, closed, oriented outward).
  void set_volume(const Mesh& volume);
  // Draws `live` from now on (render/live_volume.h): each render() makes its vertices from its
  // shadow maps as they then are, as `draw` says, and draws them with the volume pass. `live`
  // must outlive its use here (until the next set_volume); its light should be the scene's.
  // Errors: the live vertex stage does not compile (a driver problem).
  Status set_volume(const LiveVolume& live, LiveDraw draw = LiveDraw::two_pass);

  // Reads the visible surface from `texture` from the next render() on, instead of the scene's
  // `surface` distances (uploaded by create): a 2D GL_R32F texture of the camera's size, each
  // texel the distance along its pixel's ray to the visible surface (3e38 where nothing was hit),
  // row 0 at the bottom as GL renders it: what the shader's LIGHTVOL_SURFACE_* stages draw
  // (docs/engines.md). Its contents may change between frames without a call (an engine's moving
  // objects); it must outlive its use here. 0 goes back to the scene's distances. Errors, naming
  // the texture, and the renderer then keeps what it had: not a 2D texture, not the camera's size,
  // a format other than GL_R32F.
  Status set_surface(GLuint texture);

  // Draws the volume and the resolve pass, waits for the GPU, and returns the airlight image
  // (first row = top). `seconds`, when given, receives the wall-clock time of the GPU work
  // (draw + resolve + glFinish, not the read-back).
  Image render(double* seconds = nullptr);

 private:
  GlVolumeRenderer() = default;
  struct State;
  std::unique_ptr<State> state_;
};

// The F(u, v) table as uploaded: `rows` values of u = u_max·(i/(rows−1))², `cols` values of
// v = (π/2)·j/(cols−1), row-major. Computed once per process by cumulative Gauss–Legendre.
struct SunTable {
  int rows = 0, cols = 0;
  double u_max = 0;
  std::vector<float> values;
};
const SunTable& sun_table();

// Uploads the common per-pixel ray and medium uniforms shared by the GPU renderers' shaders
// (`kGlslCommon`): camera, light, medium, phase. The program must be in use.
void set_scene_uniforms(const gl::Program& program, const RenderScene& scene);
// GLSL source (no #version line) of the shared helpers: pixel_ray(), phase(), the point-light
// closest-point setup, Gauss–Legendre quadrature and the F-table lookup.
extern const char* const kGlslCommon;
// Surface distances as an R32F texture in GL row order (+infinity stored as 3e38).
gl::TextureHandle make_surface_texture(const RenderScene& scene);
// Image rows (first = top unless flip_y) from GL rows (first = bottom) read by Framebuffer::read,
// which already flips to top-first; this undoes that for flip_y cameras.
Image image_from_gl(const RenderScene& scene, const std::vector<float>& top_first);

}  // namespace lightvol
