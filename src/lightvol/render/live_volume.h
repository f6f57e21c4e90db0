// The live light volume (docs/rendering.md, "Live volumes"): the static volume of a spot,
// directional or omni light made on the GPU, every frame, from shadow maps already on the GPU, the
// way the paper's real-time system makes it: no vertex buffer, no read-back and no allocation per
// frame. The airlight's vertex stage (shaders/airlight.glsl, LIGHTVOL_LIVE_VOLUME_VERTEX) places
// vertex gl_VertexID where `lightvol build` places vertex gl_VertexID of its static volume of the
// same map (texel centres, depth encodings, the clamps to near and far, the spot's fan and the
// directional walls and cap, the omni faces' seams and corners); the triangles are build's
// (static_volume_indices, omni_volume_indices), uploaded once per map size.
// GlVolumeRenderer::set_volume(const LiveVolume&) draws it.
//
// Precision: the GPU computes in float what build computes in double and rounds to float. Each
// vertex is a convex blend of its texel ray's near and far points (window depth blends them
// homogeneously, (1 − d)·near + d·far, so no term cancels however far the far plane is), moved by
// the light's eye-to-world matrix; every step rounds relative to the coordinates it combines, so
// a vertex is within a few tens of float ulps of the largest coordinate of the frustum (its far
// corners, the light's position) of build's: below 1e-5 of it by two orders of magnitude.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/gl/context.h>
#include <lightvol/light/light.h>

namespace lightvol {

// A shadow map on the GPU: a 2D texture, level 0 `width` × `height` texels, as the light's
// projection rendered it (texture row 0 at the bottom, NDC y = −1: GL's own order; the light's
// flip_y tells how an image file of the same map is stored, not the texture). Its internal format
// is a depth format (compare mode GL_NONE; window depth only) or GL_R32F (any encoding).
struct GlShadowMap {
  GLuint texture = 0;
  int width = 0, height = 0;
};

// `depth`, a map of `light` as image files store it (first row the top of the light's view unless
// flip_y), as a GL_R32F texture in GlShadowMap's layout: for tools and tests that start from a
// file. Engines hand their own depth pass's texture to LiveVolume instead.
gl::TextureHandle upload_shadow_map(const Light& light, const DepthImage& depth);

// How the live volume tessellates the map.
struct LiveOptions {
  // Unset: the static volume (every texel a vertex). Set: the adaptive volume at this bound E
  // (world units, finite, >= 0), made by compute shaders every frame: `lightvol build --adaptive
  // --tessellation quadtree --max-error E`'s quadtree (the same cells, balance, fix-up and
  // configurations: the same triangles), closed as build closes it, drawn with an indirect draw
  // whose count the GPU writes. Every texel's point lies within E of its ray's point on the
  // volume. Spot, directional and omni lights (omni: each face tessellated in the seam rounds of
  // build's adaptive omni volume, the seams and corners closed as build closes them), window
  // depth or linear depth (docs/rendering.md).
  std::optional<double> max_error;
  // The most fix-up rounds (splitting leaves whose configuration breaks E) a frame runs, 1..63;
  // rounds after the first that splits nothing cost nothing. read_mesh() tells whether a frame
  // converged.
  int max_rounds = 32;
  // Omni: the most seam rounds (each face tessellated again with the border vertices its seams'
  // other faces have) a frame runs, 1..64; rounds after the borders agree cost nothing but their
  // (empty) dispatches. Unconverged, the seams still close the volume (each zips its two
  // borders), but E may not hold along them: read_mesh() tells.
  int max_seam_rounds = 8;
};

// A generated volume read back (LiveVolume::read_mesh; tests and tools only).
struct LiveMesh {
  Mesh mesh;  // world space; static: build's vertices and triangles; adaptive: the grid's
              // vertices in texel order, then the closing's
  std::vector<std::uint32_t> vertex_texels;  // adaptive: per grid vertex, row * W + col
                                             // (omni: face * W * W + row * W + col)
  std::uint64_t grid_triangles = 0;          // adaptive: triangles before the closing
  int fixup_rounds = 0;                      // adaptive: rounds that split a leaf (omni: on a face)
  bool converged = true;    // adaptive: the last round allowed split nothing (the bound holds);
                            // omni: on every face, and the seams' borders agree
  int seam_rounds = 0;      // adaptive omni: seam rounds run (OmniAdaptiveDetail::seam_rounds)
  bool seams_agree = true;  // adaptive omni: the last seam round changed no border
};

namespace detail {
class LiveAdaptive;
}

class LiveVolume {
 public:
  // For `light` (its `depth` says how the maps' texels encode depth) and its maps: one for a spot
  // or directional light, six square faces of one size for an omni light (+X −X +Y −Y +Z −Z, each
  // rendered with omni_face_view and the light's projection). Compiles the capture program and
  // uploads build's triangles for the maps' size. Errors: set_shadow_maps'.
  // With options.max_error, the adaptive volume (LiveOptions); errors also: a bound that is not
  // finite and >= 0, rounds outside 1..63, seam rounds outside 1..64, a radial depth encoding.
  static Result<std::unique_ptr<LiveVolume>> create(const Light& light,
                                                    const std::vector<GlShadowMap>& maps,
                                                    const LiveOptions& options = {});
  static Result<std::unique_ptr<LiveVolume>> create(const Light& light, const GlShadowMap& map,
                                                    const LiveOptions& options = {}) {
    return create(light, std::vector<GlShadowMap>{map}, options);
  }
  ~LiveVolume();

  // Uses `maps` from the next frame on. Their contents may change between frames without a call
  // (that is the point); a new size rebuilds the triangles (the only allocation). Errors, each
  // naming the texture (and the omni face): the wrong number of maps for the light, omni faces
  // not square or of different sizes, not a 2D texture, a size other than the one given or under
  // 2 × 2, a format other than a depth format or GL_R32F, a depth format with a linear or radial
  // encoding, a depth compare mode on.
  Status set_shadow_maps(const std::vector<GlShadowMap>& maps);
  Status set_shadow_map(const GlShadowMap& map) { return set_shadow_maps({map}); }

  // Opt-in, for an engine's debug builds and for tests, never per frame (it reads the maps back):
  // the maps checked again as set_shadow_maps checks them (a texture deleted, or reallocated at
  // another size or format since), then every texel as build checks a depth image: the first
  // NaN, infinite or negative depth is an Error naming the texture (and omni face) and the pixel
  // (column, row as an image file of the map stores it). The frame itself never fails on a
  // texel: a NaN one gives its texel's near-plane point (no light where the depth is unknown),
  // any other depth is clamped to the near and far planes (docs/rendering.md).
  Status validate() const;

  const Light& light() const;
  const std::vector<GlShadowMap>& shadow_maps() const;
  // build's counts for the map (static_volume_counts); adaptive: the most a map of this size can
  // give (what the buffers hold; read_mesh() tells what a frame made).
  std::uint64_t num_vertices() const;
  std::uint64_t num_triangles() const;
  bool adaptive() const;

  // For tests and tools, never in a frame: the vertices the GPU makes from the map as it is now,
  // captured by transform feedback and read back (xyz floats, world space, build's order).
  Result<std::vector<float>> read_positions() const;

  // Makes the vertices from the maps as they are now into the volume's own vertex buffer by
  // transform feedback (rasterization off; each vertex once), for drawing as a mesh from
  // mesh_vertex_array(). Leaves its own 1×1 framebuffer bound. No allocation.
  void generate() const;
  // A vertex array whose attribute 0 is that buffer (xyz floats) and whose element buffer holds
  // the triangles.
  GLuint mesh_vertex_array() const;
  // Draws what generate() made as triangles from mesh_vertex_array() (static: glDrawElements;
  // adaptive: glDrawElementsIndirect, the count written by the GPU), with the program in use.
  void draw_mesh() const;
  // For tests and tools, never in a frame: generate(), then the mesh read back.
  Result<LiveMesh> read_mesh() const;

  // For GlVolumeRenderer: with `program` (compiled from the LIGHTVOL_LIVE_VOLUME_VERTEX stage) in
  // use, sets its live_* uniforms, binds the maps to texture units `unit`.. `unit` + 5 and binds
  // the vertex array whose element buffer holds the triangles. No allocation.
  void bind(const gl::Program& program, int unit) const;
  // Indices to draw (3 per triangle); adaptive: 0 (the GPU writes the count: draw_mesh).
  GLsizei index_count() const;

 private:
  LiveVolume() = default;
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace lightvol
