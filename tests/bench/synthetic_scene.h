// A synthetic shadow map for benchmarks: a sloped floor, box occluders, thin bars (one texel wide
// at every size) and a sphere; values in [0, 1] (smaller is nearer the light).
#pragma once

#include <lightvol/depth/depth_image.h>

namespace lightvol::bench {

DepthImage synthetic_scene(int width, int height);

}  // namespace lightvol::bench
