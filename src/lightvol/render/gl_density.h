// Heterogeneous media on the GPU (docs/design.md §6, "Media of varying density"): the density
// field in GLSL, the light-side optical-depth ("opacity") map, and the per-frame grid of the
// eye-side cumulative in-scattering that light-volume fragments look up.
#pragma once

#include <memory>

#include <lightvol/airlight/density.h>
#include <lightvol/core/result.h>
#include <lightvol/gl/context.h>
#include <lightvol/render/scene.h>

namespace lightvol {

// GLSL source (no #version line) of shaders/density.glsl: `float density(vec3 x)` and its
// uniforms.
extern const char* const kGlslDensity;
// Sets the uniforms of kGlslDensity (density_type, density_seed, ...). The program must be in use.
// A voxel grid's texture is GlDensityField's: this sets its sampler to kDensityTextureUnit only.
void set_density_uniforms(const gl::Program& program, const Density& density);

// The texture unit of a voxel grid's 3D texture (units below it are the renderers' own).
constexpr int kDensityTextureUnit = 8;

// A density on the GPU: kGlslDensity's uniforms and, for a voxel grid, its voxels as an R32F 3D
// texture (fetched texel by texel: the trilinear filtering is kGlslDensity's, in float, as the C++
// one).
class GlDensityField {
 public:
  // Errors: a grid larger than the driver's 3D textures, naming the grid's source.
  static Result<std::shared_ptr<const GlDensityField>> create(const Density& density);
  ~GlDensityField();
  // Sets kGlslDensity's uniforms in `program` (in use) and binds the texture.
  void bind(const gl::Program& program) const;
  // Binds the grid's texture to kDensityTextureUnit (nothing for other densities): before each
  // draw or dispatch of a program that samples the density.
  void bind_texture() const;

 private:
  GlDensityField() = default;
  Density density_;
  gl::TextureHandle texture_;
};

// ---- the opacity map ----------------------------------------------------------------------------

// The light-side optical depth τ_L(x) = σt ∫ρ along the light's path to x, on a grid in the
// light's own frame: `size`² columns per face (texel-centre rays of the light's projection; omni:
// six 90° faces) by `layers` samples along each column, uniform in the distance from the light
// (directional: the depth below its near plane), cumulative, made by a compute shader each frame.
// Looked up trilinearly (float weights), it is exact for a constant density.
struct OpacityMapOptions {
  int size = 64;
  int layers = 64;
  int substeps = 4;  // midpoint samples of ρ per layer
};

// GLSL (no #version line) of `float light_optical_depth(vec3 x)`, reading the map bound by
// GlOpacityMap::bind (shader storage binding 3): shaders/density_grid.glsl (the web viewer's
// too) with LIGHTVOL_OPACITY_LOOKUP and its om_fetch on that buffer. Goes after kGlslDensity; a
// "#define LIGHTVOL_DENSITY_INTEGRAND" before it adds the file's d_integrand.
extern const char* const kGlslOpacityLookup;

class GlOpacityMap {
 public:
  // Compiles the compute program. Errors: a shader that does not compile (a driver problem).
  // `reach`, when positive, limits the layers to that distance from the light (directional: depth
  // below its near plane), the farthest point a renderer will look up.
  // `field`, when given, is the medium's density on the GPU, shared with the caller's programs
  // (else the map makes its own).
  static Result<std::unique_ptr<GlOpacityMap>> create(
      const Light& light, const Medium& medium, const OpacityMapOptions& options, double reach = 0,
      std::shared_ptr<const GlDensityField> field = nullptr);
  ~GlOpacityMap();
  // Recomputes the map (a compute dispatch and a barrier).
  void update() const;
  // Binds the map for kGlslOpacityLookup and sets its uniforms in `program`, which must be in use.
  void bind(const gl::Program& program) const;

 private:
  GlOpacityMap() = default;
  struct State;
  std::unique_ptr<State> state_;
};

// ---- the in-scattering grid ---------------------------------------------------------------------

// The eye-side cumulative in-scattering, per frame, on a camera-aligned grid: one column per
// `tile`×`tile` pixels (along the ray through the tile's centre) by `slices` samples from the eye
// up to the farthest surface (or light bound) the column's pixels see, uniform in the distance
// (directional light) or in a blend of the distance and the angle at the light (point light: dense
// where the ray passes the light, so that the in-scattering's 1/d² peak is resolved).
// A column stores D(t) = F(t) − F_hom(t) and its derivative in that coordinate: the heterogeneous
// cumulative integral minus the homogeneous one the volume fragments already compute exactly, so
// that a constant density gives the homogeneous image; for a point light times the column ray's
// distance h to the light. Fragments read D bilinearly across columns and by cubic Hermite
// interpolation across slices; a point light's columns at their points seen from the light at the
// fragment's angle from its ray's origin, the sum divided by the fragment's h (docs/design.md §6,
// "Columns wider than a pixel"). The automatic tile (tile = 0) is one pixel while the grid stays
// within 2^25 samples, larger beyond.
struct DensityGridOptions {
  int tile = 0;
  int slices = 128;
  int substeps = 2;  // midpoint samples per slice
  OpacityMapOptions opacity;
};

class GlDensityGrid {
 public:
  // Errors: a shader that does not compile (a driver problem), options out of range.
  static Result<std::unique_ptr<GlDensityGrid>> create(const RenderScene& scene,
                                                       const DensityGridOptions& options);
  ~GlDensityGrid();
  // Recomputes the opacity map and the grid.
  void update() const;
  int tile() const;  // the tile in use
  // Binds the grid (shader storage bindings 4 and 5) and sets airlight.glsl's LIGHTVOL_DENSITY
  // uniforms in `program`, which must be in use.
  void bind(const gl::Program& program) const;

 private:
  GlDensityGrid() = default;
  struct State;
  std::unique_ptr<State> state_;
};

// The distance along `ray` at which it leaves the light's bounds (spot and directional: the box of
// the frustum in the light's eye space, the spot's reaching its apex; omni: the cube of half-size
// far around the light); 0 when it misses them.
double light_bounds_exit(const Light& light, const Vec3d& origin, const Vec3d& direction);

// The farthest from the light (directional: the deepest below its near plane) that any pixel ray
// of `scene` gets before its surface or the light's bounds, with 0.1 % to spare: the opacity map's
// reach for that camera.
double light_reach(const RenderScene& scene);

}  // namespace lightvol
