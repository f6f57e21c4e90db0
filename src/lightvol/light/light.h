// The light description (LIGHT.json, docs/design.md §2) and the mapping from shadow-map texels
// to points.
//
// Frames: *world*; the light's *eye* space (OpenGL: the light looks down its −Z, +Y up); *NDC*
// after the projection; *window depth* d in [0, 1] with z_ndc = 2d − 1. The first stored image row
// is NDC y = +1 unless flip_y. Texel (col, row) is sampled at its centre:
// x_ndc = 2(col + ½)/W − 1, y_ndc = 1 − 2(row + ½)/H.
#pragma once

#include <array>
#include <string>
#include <string_view>

#include <lightvol/core/math.h>
#include <lightvol/core/result.h>

namespace lightvol {

enum class LightType { spot, directional, omni };
enum class DepthEncoding {
  window,  // OpenGL window depth, glDepthRange(0, 1)
  linear,  // eye-space distance along the light's view axis (−z_eye)
  radial,  // Euclidean distance to the light position (the eye origin)
};

std::string_view to_string(LightType type);
std::string_view to_string(DepthEncoding encoding);

struct Light {
  LightType type = LightType::spot;
  DepthEncoding depth = DepthEncoding::window;
  bool flip_y = false;
  Mat4d view;        // world → light eye (omni: translation to the light; faces rotate further)
  Mat4d projection;  // light eye → clip (omni: the 90° face projection)
  double near = 0;   // eye-space distances of the near and far planes, near < far
  double far = 1;
  Vec3d position;   // world: the light (spot, omni) or the view origin (directional)
  Vec3d direction;  // world, unit: where the light looks (spot, directional)

  bool is_perspective() const { return type != LightType::directional; }
};

// Parses a light description. `source` names the file in error messages. Every problem is an
// Error naming the source and the key: unknown or missing keys, wrong types, fov outside
// (0°, 180°), near ≥ far, zero or parallel up vectors, empty ortho extents, singular matrices.
Result<Light> parse_light(std::string_view json_text, const std::string& source);

// Reads and parses a light description file.
Result<Light> load_light(const std::string& path);

// Empty when a W×H image has square texels under `light`'s projection, within a texel of
// rounding (W/aspect or H·aspect off by at most one texel); else a one-line note naming both
// aspects. The aspect is the view's width over its height (spot: "aspect"; directional: the ortho
// extents). Non-square texels do not make a volume wrong (each texel's ray comes from the
// projection), but they are usually a light description whose aspect is not the image's.
std::string aspect_mismatch(const Light& light, int width, int height);

// Omni faces in the order +X −X +Y −Y +Z −Z, and their file-name tags (px nx py ny pz nz).
inline constexpr int kOmniFaces = 6;
std::string_view omni_face_tag(int face);
// World → eye of omni face `face`: a 90° camera at the light with the look/up of docs/design.md §2.
Mat4d omni_face_view(const Light& light, int face);

// The box around all the light reaches, in its eye space: the frustum's box (a perspective
// pyramid's reaches its apex, z = 0); for an omni light the cube of half-size `far` around it.
struct EyeBox {
  Vec3d lo, hi;
};
EyeBox light_eye_box(const Light& light);

// Output frame of a volume.
enum class Space { world, light };

// The light in the output frame of a volume built in `space`: what the volume is checked against
// (check_volume_linear's proof), what the float32 guard judges it with, and what a GLB of it
// records. Unchanged for world space; in light space at the origin, looking down −Z (omni: world
// axes at the origin), with the identity view (the frame is the light's eye space).
Light light_in_space(const Light& light, Space space);

// Maps the texels of one W×H depth image of a light (an omni light: of one face) to points.
class Unprojector {
 public:
  // `face` is the omni face (0..5) and ignored for other lights. `space` chooses the output frame:
  // world, or the light's eye space (omni: world axes, origin at the light).
  Unprojector(const Light& light, int width, int height, int face, Space space);

  // The point of texel (col, row) whose stored depth is `depth` (finite and ≥ 0; the caller
  // checks). Depths at or beyond the far plane give the far plane's point, depths before the near
  // plane the near plane's; for a directional light, depths at or before its near plane give the
  // point min_t() of the way down the ray instead, so that no vertex lies in the cap's plane (see
  // min_t()). Returns false only for a radial depth that a parallel (directional) ray never
  // reaches: one smaller than the ray's distance from the light position. A perspective ray
  // starts at the light, so it reaches every radial depth: 0 and 1e-39 give the near plane's point.
  bool point(int col, int row, double depth, Vec3d* out) const;

  // The points of a whole row of `width` texels, as float xyz triples into `out` (3·width floats):
  // the same points as point(), computed faster. Returns the first column point() would refuse,
  // or −1 (that column's triple is then its near-plane point).
  int row_points(int row, const float* depths, float* out) const;

  // The smallest parameter t along a texel's near→far segment that point() returns: 0, except for a
  // directional light, whose volume is capped on its near plane. There a vertex on the near plane
  // would make zero-height walls and grid faces lying on the cap, so vertices keep a distance of
  // 64 float ulps of the largest coordinate the volume can have: well above the rounding the checks
  // tolerate, far below any depth difference a shadow map resolves.
  double min_t() const { return min_t_; }

  // The texel ray's points on the near and far planes, in the output frame.
  Vec3d near_point(int col, int row) const;
  Vec3d far_point(int col, int row) const;

  // The light's apex in the output frame (spot, omni): the fan's common vertex.
  Vec3d apex() const { return to_out_.transform_point({0, 0, 0}); }

  // True when the triangles (a, b, c) and (b, d, c) of the texel quad a=(i,j), b=(i+1,j),
  // c=(i,j+1), d=(i+1,j+1) face away from the light in the output frame; false when they face it
  // (a mirrored projection, flip_y or a mirroring view) and must be wound the other way.
  bool standard_winding() const { return standard_winding_; }

 private:
  Vec3d ndc(int col, int row) const;
  Vec3d eye_near(int col, int row) const;
  Vec3d eye_far(int col, int row) const;

  DepthEncoding depth_;
  bool perspective_;
  bool flip_y_;
  int width_, height_;
  Mat4d inv_projection_;  // clip → eye
  Mat4d to_out_;          // eye → output frame
  Mat4d clip_to_out_;     // clip → output frame (window depth)
  bool standard_winding_ = true;
  double min_t_ = 0;
};

}  // namespace lightvol
