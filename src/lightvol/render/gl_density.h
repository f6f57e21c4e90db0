// Heterogeneous media on the GPU (docs/design.md §6, "Media of varying density"): the density
// field in GLSL, the light-side optical-depth map, and the per-frame grid of the eye-side
// cumulative in-scattering that light-volume fragments look up.
#pragma once

#include <lightvol/airlight/density.h>
#include <lightvol/gl/context.h>

namespace lightvol {

// GLSL source (no #version line) of shaders/density.glsl: `float density(vec3 x)` and its
// uniforms.
extern const char* const kGlslDensity;
// Sets the uniforms of kGlslDensity (density_type, density_seed, ...). The program must be in use.
void set_density_uniforms(const gl::Program& program, const Density& density);

}  // namespace lightvol
