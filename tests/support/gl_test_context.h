// One headless GL context per test binary. GL tests skip, with the reason, only where none can be
// created; with LIGHTVOL_REQUIRE_GL=1 in the environment (.ci/run sets it) that is a failure
// instead, so that a machine whose OpenGL broke cannot pass with no rendering tested.
#pragma once

#include <cstdlib>
#include <cstring>
#include <memory>

#include <gtest/gtest.h>

#include <lightvol/gl/context.h>

namespace lightvol::test {

inline Result<std::unique_ptr<gl::Context>>& gl_test_context() {
  static Result<std::unique_ptr<gl::Context>> context = gl::Context::create();
  return context;
}

// LIGHTVOL_REQUIRE_GL is set and not "0": a test that cannot have a context fails.
inline bool gl_required() {
  const char* value = std::getenv("LIGHTVOL_REQUIRE_GL");
  return value != nullptr && *value != '\0' && std::strcmp(value, "0") != 0;
}

}  // namespace lightvol::test

// Skips (or, under LIGHTVOL_REQUIRE_GL=1, fails) the test when there is no context.
#define REQUIRE_GL_CONTEXT()                                                                   \
  if (::lightvol::test::gl_test_context()) {                                                   \
  } else if (::lightvol::test::gl_required())                                                  \
    GTEST_FAIL() << "LIGHTVOL_REQUIRE_GL is set and there is no headless OpenGL 4.5 context: " \
                 << ::lightvol::test::gl_test_context().error().message;                       \
  else                                                                                         \
    GTEST_SKIP() << "no headless OpenGL 4.5 context: "                                         \
                 << ::lightvol::test::gl_test_context().error().message
