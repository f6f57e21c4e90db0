// The visible surfaces in a picture, beside the airlight: the demo's lit scene, and surfaces of
// constant radiance (`lightvol render --composite`). Both are seen through the medium: a surface
// at distance s along a pixel ray contributes its radiance times e^(−σt·s).
#pragma once

#include <vector>

#include <lightvol/render/scene.h>

namespace lightvol {

// How lit_surfaces shades: Lambert surfaces of albedo `albedo`, plus an `ambient` radiance.
struct SurfaceShading {
  double albedo = 0.35;
  double ambient = 0.003;
};

// `airlight` plus the surfaces of `scene` lit by its spot light: irradiance I·cos θ / d² ·
// e^(−σt·d) at distance d from the light where the shadow map says the point is lit (its eye depth
// within 1% + 0.02 of the map's), reflected by a Lambert surface; normals from the camera's
// surface distances (the cross product of the tangents toward the nearer neighbour in depth
// along each axis, turned to face the camera). `shadow_window`: the light's W×H shadow map as
// window depth (DepthPasses::window_depth). The airlight image has the camera's size. In a medium
// of varying density both attenuations are e^(−σt ∫ρ) along the segments (4-point Gauss–Legendre
// panels of twice the density's finest wavelength: a picture's accuracy), each pixel on its own
// (TBB); the light's side only when `shading.albedo` is not 0.
Image lit_surfaces(const RenderScene& scene, const std::vector<float>& shadow_window, int width,
                   int height, const Image& airlight, const SurfaceShading& shading = {});

// Adds to `image` (the camera's size) surfaces of constant radiance `radiance` at the scene's
// surface distances, seen through its medium: times e^(−σt·s), or in a medium of varying density
// e^(−σt ∫ρ) along the pixel's ray to the surface (lit_surfaces' panels), each pixel on its own
// (TBB).
void add_constant_surfaces(const RenderScene& scene, double radiance, Image* image);

// A tone-mapping exposure (write_image's `exposure`) that maps the 99.5th percentile of the
// image's positive values to `target`; 1 when no value is positive. One exposure for several
// pictures makes them compare by eye.
double percentile_exposure(const Image& image, double target);

}  // namespace lightvol
