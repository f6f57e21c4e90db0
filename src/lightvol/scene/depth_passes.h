// Depth passes of one scene, whichever way they are rendered: on the GPU (gl_depth_passes in
// scene/shadowmap.h) or by CPU ray casting (cpu_depth_passes). What `lightvol shadowmap` and
// `lightvol demo` render: shadow maps of a light and the depth of a camera.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>
#include <lightvol/depth/shadow_maps.h>
#include <lightvol/light/light.h>
#include <lightvol/scene/scene.h>

namespace lightvol {

class DepthPasses {
 public:
  virtual ~DepthPasses() = default;

  // How the passes are rendered: "OpenGL" or "CPU ray casting".
  virtual std::string method() const = 0;

  // Window depth of one W×H pass of `view` (omni: face `face`), row-major as stored: first row =
  // top of the view (NDC y = +1) unless the view's flip_y; 1 where nothing was hit (as
  // ShadowMapRenderer::render_window_depth and raycast_window_depth give it). `gpu_seconds`,
  // when given, receives the wall-clock time of the GPU work (0 on the CPU).
  virtual Result<std::vector<float>> window_depth(const Light& view, int width, int height,
                                                  int face, double* gpu_seconds = nullptr) = 0;
};

// Ray casting in double precision (scene/raycast.h) through a BVH built at the first pass.
// `scene` must outlive the object.
std::unique_ptr<DepthPasses> cpu_depth_passes(const Mesh& scene);

// Every pass of a view (pass_count: one, or six omni faces), rendered and encoded.
struct RenderedPasses {
  std::vector<std::vector<float>> window;  // per pass, window depth (DepthPasses::window_depth)
  ShadowMaps maps;                         // the same in the view's depth encoding (encode_depth)
  double gpu_seconds = 0;                  // summed over the passes (0 on the CPU)

  // Fraction of texels, over all passes, where something was hit (window depth < 1).
  double hit_fraction() const;
};
Result<RenderedPasses> render_passes(DepthPasses& passes, const Light& view, MapSize size);

}  // namespace lightvol
