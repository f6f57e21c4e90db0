// One headless GL context per test binary; GL tests skip, with the reason, only where none can be
// created.
#pragma once

#include <memory>

#include <gtest/gtest.h>

#include <lightvol/gl/context.h>

namespace lightvol::test {

inline Result<std::unique_ptr<gl::Context>>& gl_test_context() {
  static Result<std::unique_ptr<gl::Context>> context = gl::Context::create();
  return context;
}

}  // namespace lightvol::test

#define REQUIRE_GL_CONTEXT()                         \
  if (!::lightvol::test::gl_test_context())          \
  GTEST_SKIP() << "no headless OpenGL 4.5 context: " \
               << ::lightvol::test::gl_test_context().error().message
