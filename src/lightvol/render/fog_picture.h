// A picture of a light's shafts in a medium of varying density beside the homogeneous medium:
// what `lightvol demo` writes as demo_fog.png (docs/rendering.md). Needs a current gl::Context.
#pragma once

#include <array>
#include <string>
#include <vector>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>
#include <lightvol/render/gl_volume.h>
#include <lightvol/render/scene.h>

namespace lightvol {

// The colours of the picture: the light's (warm) for the airlight and the surfaces it lights, a
// cool ambient radiance on every surface, and the exposure (the tone-mapped value x/(1+x) of the
// homogeneous half's 99.5th percentile; the fog half shares its exposure).
struct FogPictureOptions {
  std::array<double, 3> light_colour{1.0, 0.72, 0.42};
  std::array<double, 3> ambient_colour{0.5, 0.62, 0.9};
  double ambient = 0.0002;
  double exposure = 1.2;
  // The renderer's options; the fog's in-scattering grid has columns of `grid_tile`² pixels (2:
  // a quarter of the work of one per pixel, for the demo's time on a CPU's OpenGL).
  GlVolumeOptions volume;
  int grid_tile = 2;
};

struct FogPicture {
  double fog_seconds = 0;  // the fog's airlight on the GPU (its grid, opacity map and volume pass)
  double fog_airlight_ratio = 0;  // Σ airlight in the fog / Σ in the homogeneous medium
};

// Renders `volume`'s airlight in scene.medium (homogeneous: its density is ignored) and in `fog`
// (a medium of varying density), each over the surfaces the light reaches (lit_surfaces, with
// `shadow_window`, the light's map_width × map_height shadow map as window depth) plus the ambient
// light, in colour, and writes them side by side to `path` (homogeneous on the left, an image
// twice the camera's width). `homogeneous`, when given, is `volume`'s airlight in scene.medium,
// rendered already. Errors: the GPU renderer's, the writer's (naming `path`).
Result<FogPicture> write_fog_picture(const RenderScene& scene, const Mesh& volume,
                                     const Medium& fog, const std::vector<float>& shadow_window,
                                     int map_width, int map_height, const std::string& path,
                                     const FogPictureOptions& options = {},
                                     const Image* homogeneous = nullptr);

}  // namespace lightvol
