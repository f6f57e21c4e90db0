// Shared by the adaptive tessellation and adaptive volume tests: an independent measure of a
// volume's error (every texel's ray cast against the mesh) and the depth maps they run on.
#pragma once

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include <lightvol/core/mesh.h>
#include <lightvol/depth/cube_faces.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/light/light.h>

namespace lightvol::test {

struct RayErrors {
  double max_error = 0;
  int missed = 0;  // texels whose ray hits no grid triangle
};

// Projects each triangle of the volume into the light's texel space (through the light's own
// matrices), drops the closing (vertices on the near plane or at the light), and intersects every
// texel ray its footprint covers (Möller–Trumbore in double). The farthest hit along the ray is
// the volume's surface there; its distance to the texel's true point is the texel's error. A
// texel no triangle covers is a test failure (the first five are reported).
RayErrors ray_errors(const Mesh& mesh, const Light& light, const DepthImage& depth);

// The largest distance, over every texel of every face of an omni light's `cube`, between the
// texel's point and where its ray (from the light) leaves `mesh`: brute force over all triangles
// (small maps only). A ray that leaves no triangle is a test failure.
double omni_ray_error(const Mesh& mesh, const Light& light, const CubeFaces& cube);

// Linear depth (world units along the view axis) of a scene under the test lights: a sloped floor,
// box occluders with sharp edges, 1-texel bars, a sphere.
DepthImage adaptive_scene(int w, int h, double floor_depth);

// Window depths of the same kind of scene, for a window-encoded spot light.
DepthImage window_scene(int w, int h);

// An orthographic light over the unit square from depth 0 to 1, linear: the window depth is the
// stored value, so the depths are floats and can be the image's own.
std::string unit_box_json();

// A light (JSON) and the stored values [lo, hi] its maps below take.
struct LightRange {
  std::string light;
  double lo, hi;
};

// Every kind of projection: spot window and linear (per-texel error scales), directional window
// and the unit light box (uniform).
std::vector<LightRange> light_ranges();

// A smooth surface between range.lo and range.hi, plateaus with steps (64 heights drawn from `rng`)
// in the lower right quarter and a cliff along column w / 3: leaves of many levels, fix-up rounds,
// and sizes not 2^k + 1 give clipped cells. With `jitter` > 0, noise of up to jitter × (hi − lo)
// on every texel, also drawn from `rng`.
DepthImage plateau_scene(int w, int h, const LightRange& range, std::mt19937& rng,
                         double jitter = 0);

// White noise where nothing coarsens: each texel lo + span × u, u uniform in [0, 1) from a linear
// congruential generator whose `state` goes on from map to map.
DepthImage white_noise(int w, int h, float lo, float span, std::uint32_t& state);

// Closed, oriented, no degenerate triangle, positive volume (as gtest expectations).
void expect_valid_volume(const Mesh& mesh);

}  // namespace lightvol::test
