// The CPU reference for depth passes: exact ray casting of a scene at texel centres, in double
// precision, through the BVH of render/bvh.h. Slow next to the GL pass (scene/shadowmap.h); it is
// what that pass is tested against, and a fallback where no OpenGL context can be created.
#pragma once

#include <vector>

#include <lightvol/core/mesh.h>
#include <lightvol/light/light.h>
#include <lightvol/scene/bvh.h>

namespace lightvol {

// Window depth (glDepthRange(0, 1)) of the first surface along the ray of each texel centre of a
// W×H pass of `light` (omni: face `face`), between the near and far planes; 1 where the ray meets
// nothing before the far plane. Row-major, first row = top of the view (NDC y = +1) unless the
// light's flip_y, as the GL pass stores it. `bvh` is built over the scene mesh. Rows run in
// parallel (TBB).
std::vector<double> raycast_window_depth(const Bvh& bvh, const Light& light, int width, int height,
                                         int face);

// The window depth of the first hit along the ray through image point (x, y) of a W×H pass, in
// texel units from the top-left corner of the stored image: texel (col, row)'s centre is
// (col + ½, row + ½), and that point gives the entry above. Off-centre points probe silhouettes.
double raycast_point(const Bvh& bvh, const Light& light, int width, int height, int face, double x,
                     double y);

}  // namespace lightvol
