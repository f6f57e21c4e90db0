// Renderers on a context they cannot use (issue 23, bad input): with no context current and on an
// OpenGL 3.3 context (llvmpipe made to offer 3.3 by MESA_GL_VERSION_OVERRIDE, so its own binary:
// Mesa reads the variable once per process), every renderer's create returns an Error naming what
// it needs and what the context is, before any other GL call: no GL error, no crash.
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/gl/context.h>
#include <lightvol/render/gl_volume.h>
#include <lightvol/render/live_volume.h>
#include <lightvol/scene/shadowmap.h>

#include "support/analytic_scene.h"
#include "support/gl_test_context.h"
#include "support/test_support.h"

namespace lightvol {
namespace {

using namespace gl;

TEST(ContextVersion, RenderersRefuseNoContextAndAnOldOneNamingBoth) {
  const Light light = test::light_from_json(test::spot_json("linear"));
  const RenderScene scene =
      test::make_render_scene(test::make_camera({6, 3, 6}, {0, 1, 0}, 32, 24), light, Medium{});
  const GlShadowMap map{1, 32, 32};
  const auto errors = [&] {
    std::vector<std::string> e;
    Result<std::unique_ptr<LiveVolume>> live = LiveVolume::create(light, map);
    e.push_back(live ? "accepted" : live.error().message);
    Result<std::unique_ptr<GlVolumeRenderer>> renderer = GlVolumeRenderer::create(scene);
    e.push_back(renderer ? "accepted" : renderer.error().message);
    Result<ShadowMapRenderer> depth = ShadowMapRenderer::create(Mesh{});
    e.push_back(depth ? "accepted" : depth.error().message);
    Status compute = require_context(4, 3, true, "adaptive live volume");
    e.push_back(compute ? "accepted" : compute.error().message);
    return e;
  };

  // No context yet in this process (lightvol's functions not even loaded).
  const std::string none =
      "no OpenGL context is current on this thread (lightvol::gl::Context::create makes one and "
      "loads lightvol's OpenGL functions)";
  EXPECT_EQ(errors(),
            (std::vector<std::string>{
                "live volume: needs OpenGL 4.5 core; " + none,
                "volume renderer: needs OpenGL 4.5 core; " + none,
                "shadow-map depth pass: needs OpenGL 4.5 core; " + none,
                "adaptive live volume: needs OpenGL 4.3 core with compute shaders; " + none}));

  ::setenv("MESA_GL_VERSION_OVERRIDE", "3.3", 1);
  Result<std::unique_ptr<Context>> old = Context::create({3, 3});
  if (!old) {
    if (test::gl_required()) GTEST_FAIL() << old.error().message;
    GTEST_SKIP() << "no OpenGL 3.3 context: " << old.error().message;
  }
  if ((*old)->version().rfind("3.3", 0) != 0)
    GTEST_SKIP() << "the driver gave " << (*old)->version() << " for 3.3 (not Mesa?)";
  const std::string context = "the current context is OpenGL 3.3";
  const std::string renderer = " (" + (*old)->renderer() + ")";
  EXPECT_EQ(errors(), (std::vector<std::string>{
                          "live volume: needs OpenGL 4.5 core; " + context + renderer,
                          "volume renderer: needs OpenGL 4.5 core; " + context + renderer,
                          "shadow-map depth pass: needs OpenGL 4.5 core; " + context + renderer,
                          "adaptive live volume: needs OpenGL 4.3 core with compute shaders; " +
                              context + ", without compute shaders" + renderer}));
  EXPECT_TRUE(require_context(3, 3, false, "a 3.3 renderer"));
  EXPECT_EQ(pending_error(), "");

  // Once the context is gone, none is current again.
  old->reset();
  EXPECT_EQ(errors()[0], "live volume: needs OpenGL 4.5 core; " + none);
}

}  // namespace
}  // namespace lightvol
