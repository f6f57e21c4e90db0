// The classic alternatives to light volumes, on the GPU, for comparison (docs/design.md §6):
//
// raymarch — Tóth & Umenhoffer 2009: N steps per pixel from the eye to the visible surface (within
//   the light's frustum bounds), each step's point looked up in the shadow map(s). Interleaved
//   sampling: within each M×M pixel block every pixel offsets its steps by a different fraction
//   (k + ½)/M² of a step, and a separable M-wide box gather (horizontal, then vertical) averages
//   the block, so each pixel sees M²·N distinct samples for the price of N. M = 1 is the plain
//   marcher of the blog post "Volumetric lighting 1 – A naive approach". The shadow test
//   interpolates the map's window depth over the same two triangles per texel quad as the static
//   volume, so the marcher converges to the volume's exact airlight. Spot and directional lights
//   take one map; omni lights six faces (+X −X +Y −Y +Z −Z). In a medium of varying density (the
//   seed's method) each step also samples ρ, accumulates the eye-side optical depth and reads the
//   light-side one from the opacity map (gl_density.h).
// radial — Mitchell 2007 (GPU Gems 3, ch. 13): an occlusion pre-pass from the camera depth (pixels
//   whose surface lies beyond the light, weighted by the unshadowed glow around the light,
//   σs·I·p(θ)·e^(−σt·D)/max(h, D/50), h the light's distance from the pixel ray) blurred
//   radially toward the light's screen position with exposure, weight, decay and density.
//   Approximate by design (it knows nothing of the shadow map); zero when the light is behind the
//   camera.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <lightvol/core/result.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/render/gl_density.h>
#include <lightvol/render/scene.h>

namespace lightvol {

enum class MarchMethod { raymarch, radial };

struct MarchOptions {
  MarchMethod method = MarchMethod::raymarch;
  int samples = 64;    // raymarch: steps per pixel; radial: samples along the blur line
  int interleave = 1;  // raymarch: M
  // radial blur (Mitchell's names)
  double exposure = 1.0;
  double weight = 0.0;  // 0: 1/samples
  double decay = 0.97;
  double density = 0.9;
  // raymarch in a medium of varying density: the light-side optical depths (gl_density.h)
  OpacityMapOptions opacity;
};

class GlMarcher {
 public:
  // `maps` are the light's shadow maps in its depth encoding (one, or six faces for omni), named
  // by `sources` in errors. Needs a current gl::Context on this thread for its lifetime.
  static Result<std::unique_ptr<GlMarcher>> create(const RenderScene& scene,
                                                   const std::vector<DepthImage>& maps,
                                                   const std::vector<std::string>& sources,
                                                   const MarchOptions& options);
  ~GlMarcher();

  // Renders, waits for the GPU, returns the airlight (first row = top); `seconds` gets the
  // wall-clock time of the GPU passes.
  Image render(double* seconds = nullptr);

 private:
  GlMarcher() = default;
  struct State;
  std::unique_ptr<State> state_;
};

// The shadow map(s) as OpenGL window depth (faces stacked: face f in rows [f·H, (f+1)·H), first
// stored row first), the form the marcher's shadow test interpolates.
std::vector<float> window_depth_maps(const Light& light, const std::vector<DepthImage>& maps);

}  // namespace lightvol
