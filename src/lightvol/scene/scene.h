// Scenes: the triangle meshes `lightvol shadowmap` renders, and what every depth pass over them
// shares (map sizes, the view of each pass, window depth → the light's depth encoding).
//
// A depth pass renders OpenGL window depth (glDepthRange(0, 1)) at texel centres. The GL pass
// (scene/shadowmap.h) and the CPU ray caster (scene/raycast.h) both produce window depth, first
// stored row = the top of the view (NDC y = +1) unless the light's flip_y; encode_depth() turns it
// into the light's "depth" encoding.
#pragma once

#include <string>
#include <vector>

#include <lightvol/core/math.h>
#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/light/light.h>

namespace lightvol {

// Reads a scene mesh (OBJ, PLY, OFF, STL, DRC, GLB: whatever read_mesh reads) into flat buffers.
// Beyond read_mesh's errors, the first vertex with a NaN or infinite coordinate is an Error naming
// the file and the vertex.
Result<Mesh> load_scene(const std::string& path);

// Size of the depth image(s) of width `n` for a light:
//  spot: width n, height round(n / aspect) (aspect = width / height, as in the projection);
//  directional: n × n (the texels stretch when the ortho extents are not square);
//  omni: n × n per face.
// n must lie in [2, 16384]; a spot aspect that makes the height < 2 or > 16384 is an Error naming
// `source` (the light's file).
struct MapSize {
  int width = 0;
  int height = 0;
};
Result<MapSize> shadow_map_size(const Light& light, int n, const std::string& source);

// World → eye of one depth pass: the light's view, or omni face `face`'s view.
Mat4d pass_view(const Light& light, int face);

// Number of passes a light needs: 6 for omni, else 1.
inline int pass_count(const Light& light) { return light.type == LightType::omni ? kOmniFaces : 1; }

// Converts one pass's window depths (W×H, row-major, as stored) to the light's depth encoding:
// window is kept; linear becomes −z_eye; radial |p_eye| (the distance to the light position, or
// for a directional light to its view origin). Window depths ≥ 1 ("nothing hit") become 1, the
// far distance, or the texel ray's distance to the far plane, so they still read as the far plane.
DepthImage encode_depth(const Light& light, int width, int height,
                        const std::vector<double>& window);
DepthImage encode_depth(const Light& light, int width, int height,
                        const std::vector<float>& window);

// A picture of window-depth passes for people: the passes (each W×H) stacked top to bottom, each
// texel's eye-space depth −z_eye mapped linearly from the nearest hit (1, white) to the farthest
// (0.1), and texels where nothing was hit black. Write it as a 16-bit PNG with write_depth_image.
DepthImage depth_preview(const Light& light, int width, int height,
                         const std::vector<std::vector<float>>& passes);

}  // namespace lightvol
