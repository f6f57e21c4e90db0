// The demo's steps that need OpenGL (pipeline/demo.h's DemoGpu), in lightvol::gl: depth passes
// on the GPU and the airlight pictures.
#pragma once

#include <lightvol/pipeline/demo.h>

namespace lightvol {

// The demo's GPU steps: depth passes by OpenGL (gl_depth_passes, whose context stays current for
// the pictures), and the pictures: each volume's airlight (airlight_static, airlight_adaptive;
// .exr and .png), ray marching's (airlight_raymarch; 128 samples, 2×2 interleaved), demo.png
// (the surfaces the spot lights and the static volume's airlight in the light's warm colour, the
// ambient light in a cool one) and demo_fog.png (write_fog_picture: the noise fog beside
// demo.png's medium). Every PNG has the static volume's exposure, so that they compare by eye.
DemoGpu gl_demo_steps();

}  // namespace lightvol
