// The headless GL context: a context can be had here (llvmpipe), float targets take additive
// negative contributions, programs report compile errors, and read() returns top row first; an
// engine's own loader (load_functions) loads every function, or none when it lacks one.
#include <dlfcn.h>

#include <cstring>

#include <gtest/gtest.h>

#include <lightvol/gl/context.h>

#include "support/gl_test_context.h"

namespace lightvol::gl {
namespace {

// The shared context of tests/support/gl_test_context.h.
Context* shared_context() { return test::gl_test_context()->get(); }

const char* kTriangleVs = R"(#version 450 core
void main() {
  vec2 p = vec2((gl_VertexID == 1) ? 3.0 : -1.0, (gl_VertexID == 2) ? 3.0 : -1.0);
  gl_Position = vec4(p, 0.0, 1.0);
})";

TEST(GlContext, ReportsAFourFiveCoreContext) {
  REQUIRE_GL_CONTEXT();
  EXPECT_FALSE(shared_context()->renderer().empty());
  EXPECT_EQ(shared_context()->version().rfind("4.5", 0), 0u) << shared_context()->version();
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  EXPECT_GE(major * 10 + minor, 45);
}

TEST(GlContext, AdditiveFloatBlendingTakesNegativeValues) {
  REQUIRE_GL_CONTEXT();
  Result<Program> program = Program::compile(kTriangleVs, R"(#version 450 core
uniform float value;
layout(location = 0) out float result;
void main() { result = value * (gl_FragCoord.y < 2.0 ? 1.0 : 2.0); })",
                                             "test");
  ASSERT_TRUE(program) << program.error().message;
  Result<Framebuffer> fb = Framebuffer::create(3, 4, {GL_R32F}, false);
  ASSERT_TRUE(fb) << fb.error().message;
  fb->bind();
  glClearColor(0, 0, 0, 0);
  glClear(GL_COLOR_BUFFER_BIT);
  glEnable(GL_BLEND);
  glBlendFunc(GL_ONE, GL_ONE);
  GLuint vao = 0;
  glGenVertexArrays(1, &vao);
  glBindVertexArray(vao);
  program->use();
  for (float v : {1.5f, -4.0f, 0.25f}) {
    glUniform1f(program->uniform("value"), v);
    glDrawArrays(GL_TRIANGLES, 0, 3);
  }
  glDisable(GL_BLEND);
  glDeleteVertexArrays(1, &vao);
  const std::vector<float> pixels = fb->read(0, 1);
  ASSERT_EQ(pixels.size(), 12u);
  // GL row 0 and 1 (y < 2) are the bottom two image rows; read() puts the top row first.
  for (int row = 0; row < 4; ++row)
    for (int col = 0; col < 3; ++col)
      EXPECT_FLOAT_EQ(pixels[static_cast<std::size_t>(row * 3 + col)], row >= 2 ? -2.25f : -4.5f)
          << "pixel " << col << "," << row;
  EXPECT_EQ(pending_error(), "");
}

// An engine's loader: the eglGetProcAddress of the libEGL the test context came from (as an
// engine with its own EGL context would pass it), counting its calls, refusing `g_refuse`.
using EglGetProcAddress = GlProc (*)(const char*);
EglGetProcAddress egl_get_proc_address() {
  static void* library = ::dlopen("libEGL.so.1", RTLD_NOW | RTLD_LOCAL);
  return library ? reinterpret_cast<EglGetProcAddress>(::dlsym(library, "eglGetProcAddress"))
                 : nullptr;
}
int g_calls = 0;
const char* g_refuse = nullptr;
GlProc engine_loader(const char* name) {
  ++g_calls;
  if (g_refuse != nullptr && std::strcmp(name, g_refuse) == 0) return nullptr;
  return egl_get_proc_address()(name);
}
void* sdl_style_loader(const char* name) { return reinterpret_cast<void*>(engine_loader(name)); }

#define LIGHTVOL_COUNT(type, name) +1
constexpr int kFunctions = 0 LIGHTVOL_GL_FUNCTIONS(LIGHTVOL_COUNT);
#undef LIGHTVOL_COUNT

TEST(GlContext, LoadsItsFunctionsThroughAnEnginesLoader) {
  REQUIRE_GL_CONTEXT();
  ASSERT_NE(egl_get_proc_address(), nullptr);
  // A loader without some functions: the Error names them, and no pointer changes.
  const auto draw_arrays = glDrawArrays;
  glDrawArrays = nullptr;
  g_refuse = "glDispatchCompute";
  Status refused = load_functions(engine_loader);
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().message,
            "lightvol::gl::load_functions: the loader has no glDispatchCompute");
  EXPECT_EQ(glDrawArrays, nullptr);
  EXPECT_NE(glDispatchCompute, nullptr);
  // The engine's loader, with both signatures (GLFW and EGL: a function pointer; SDL 2: void*):
  // every function asked once, every pointer set, and the current context draws through them.
  g_refuse = nullptr;
  for (const bool object : {false, true}) {
    g_calls = 0;
    glDrawArrays = nullptr;
    ASSERT_TRUE(object ? load_functions(sdl_style_loader) : load_functions(engine_loader));
    EXPECT_EQ(g_calls, kFunctions);
    EXPECT_EQ(glDrawArrays, draw_arrays);
    EXPECT_TRUE(require_context(4, 5, true, "test"));
    Result<Program> program = Program::compile(
        kTriangleVs, "#version 450 core\nout float v;\nvoid main() { v = 3.5; }\n", "test");
    ASSERT_TRUE(program) << program.error().message;
    Result<Framebuffer> fb = Framebuffer::create(2, 2, {GL_R32F}, false);
    ASSERT_TRUE(fb) << fb.error().message;
    fb->bind();
    GLuint vao = 0;
    glGenVertexArrays(1, &vao);
    glBindVertexArray(vao);
    program->use();
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glDeleteVertexArrays(1, &vao);
    const std::vector<float> pixels = fb->read(0, 1);
    EXPECT_EQ(pixels.size(), 4u);
    for (const float v : pixels) EXPECT_EQ(v, 3.5f);
    EXPECT_EQ(pending_error(), "");
  }
}

TEST(GlContext, CompileErrorsCarryTheLog) {
  REQUIRE_GL_CONTEXT();
  Result<Program> program =
      Program::compile(kTriangleVs, "#version 450 core\nvoid main() { nope; }", "broken");
  ASSERT_FALSE(program);
  EXPECT_NE(program.error().message.find("broken: fragment shader does not compile"),
            std::string::npos)
      << program.error().message;
}

}  // namespace
}  // namespace lightvol::gl
