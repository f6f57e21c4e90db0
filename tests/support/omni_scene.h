// A synthetic omni-light scene for tests and benchmarks: a light inside a box room with a pillar
// and a ball, ray-cast analytically into six cube faces (flat and curved surfaces, and depth edges,
// on every face). Window depths of the light omni_scene_light_json() describes.
#pragma once

#include <string>

#include <lightvol/depth/cube_faces.h>

namespace lightvol::test {

// {"type": "omni", "position": [0.3, 1.6, -0.4], "near": 0.05, "far": 30, "depth": "window"}
std::string omni_scene_light_json();

// The six W×W window-depth faces of the scene (+X −X +Y −Y +Z −Z, docs/design.md §2 face frames).
CubeFaces omni_scene(int width);

}  // namespace lightvol::test
