// A small analytic scene for the render tests: a floor plane y = 0 and a box occluder, with shadow
// maps, camera surface distances and visibility computed by exact ray casting.
#pragma once

#include <string>
#include <vector>

#include <lightvol/airlight/airlight.h>
#include <lightvol/core/mesh.h>
#include <lightvol/depth/cube_faces.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/light/light.h>
#include <lightvol/render/scene.h>

namespace lightvol::test {

struct Box {
  Vec3d lo{-0.5, 1.0, -0.5};
  Vec3d hi{0.5, 1.5, 0.5};
};

// Nearest t > 0 where origin + t·direction meets the floor (y = 0) or the box; +infinity if none.
double cast_scene(Vec3d origin, Vec3d direction, const Box& box = {});

// The light's shadow map of the scene in its "linear" encoding (eye-space −z; far where nothing
// is hit). The light must use depth "linear".
// Omni lights: face `face` (+X −X +Y −Y +Z −Z), its depth the face eye space's −z.
DepthImage scene_shadow_map(const Light& light, int width, int height, const Box& box = {},
                            int face = 0);

// An omni light's six size × size faces of the scene (scene_shadow_map), named as build names them.
CubeFaces scene_cube_faces(const Light& light, int size, const Box& box = {});

// True when x is lit: inside the part of the light's frustum spanned by the texel-centre rays of a
// W×H map, between near and far, and the light reaches it without meeting floor or box.
bool scene_lit(const Light& light, int width, int height, Vec3d x, const Box& box = {});

// A camera (JSON text as for parse_camera) and its RenderScene with analytic surface distances.
Camera make_camera(Vec3d position, Vec3d target, int width, int height, double fov_y_deg = 50);
RenderScene make_render_scene(const Camera& camera, const Light& light, const Medium& medium,
                              const Box& box = {});

// Views the live-volume tests draw: a spot and a directional light (their depth "linear" JSON,
// read in `encoding`), each seen from outside and from inside its volume.
struct LightViewCase {
  const char* name;
  std::string json;
  DepthEncoding encoding;
  Vec3d eye, target;
};
std::vector<LightViewCase> light_view_cases();

// The render tests' medium: σs 0.06, σa 0.02, intensity 20, Henyey–Greenstein phase g.
Medium render_test_medium(double g = 0.4);

// Brute-force airlight of one pixel: midpoint rule with `steps` samples along the ray up to the
// surface (or `max_t`), each weighted by scene_lit. Direct from docs/design.md §6's integrand;
// with a varying density, ρ and both optical depths by midpoint sums too (200 steps toward the
// light per sample).
double brute_force_airlight(const RenderScene& scene, int width, int height, int col, int row,
                            int steps, double max_t, const Box& box = {});

}  // namespace lightvol::test
