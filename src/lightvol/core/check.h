// Checks for broken internal invariants: they print what failed, with both values, and abort.
// Expected failures (bad input) are Results (core/result.h), never checks.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>

namespace lightvol::detail {

[[noreturn]] inline void check_failed(const char* file, int line, const std::string& what) {
  std::fprintf(stderr, "lightvol: internal error at %s:%d: %s\n", file, line, what.c_str());
  std::abort();
}

template <class A, class B>
std::string describe_pair(const char* expr_a, const char* op, const char* expr_b, const A& a,
                          const B& b) {
  std::ostringstream out;
  out << "check " << expr_a << ' ' << op << ' ' << expr_b << " failed: " << a << " vs " << b;
  return out.str();
}

}  // namespace lightvol::detail

#define LV_CHECK(cond)                                                                           \
  do {                                                                                           \
    if (!(cond)) ::lightvol::detail::check_failed(__FILE__, __LINE__, "check " #cond " failed"); \
  } while (0)

#define LV_CHECK_OP(a, op, b)                                                                \
  do {                                                                                       \
    const auto& lv_a_ = (a);                                                                 \
    const auto& lv_b_ = (b);                                                                 \
    if (!(lv_a_ op lv_b_))                                                                   \
      ::lightvol::detail::check_failed(                                                      \
          __FILE__, __LINE__, ::lightvol::detail::describe_pair(#a, #op, #b, lv_a_, lv_b_)); \
  } while (0)

#define LV_CHECK_EQ(a, b) LV_CHECK_OP(a, ==, b)
#define LV_CHECK_LE(a, b) LV_CHECK_OP(a, <=, b)
#define LV_CHECK_LT(a, b) LV_CHECK_OP(a, <, b)
