// Which side of a face a light sees, beyond what float rounding of its corners could change: the
// test the proof from the light (check/light_proof.cpp) makes of every face, and the float32 guard
// (volume/static_volume.cpp) of the faces it cannot settle more cheaply.
#pragma once

#include <lightvol/core/math.h>

namespace lightvol {

// A point light: `a`, `b`, `c` are the face's corners relative to the eye, `bc` = b × c and
// `det` = a · bc. +1: the light sees the face from behind (it faces away), −1: the face faces the
// light, 0: edge-on, |det| within what moving each corner by `ulp_tol` could change.
inline int side_from_point(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& bc,
                           double det, double ulp_tol) {
  const double tol = ulp_tol * (length(bc) + length(cross(c, a)) + length(cross(a, b)));
  if (det > tol) return 1;
  if (det < -tol) return -1;
  return 0;
}

// A directional light along the unit vector `f`: `area` is the face's projected area,
// 0.5 (b − a) × (c − a) · f, and `source` whether all three corners lie on the near plane. +1: an
// exit (facing along f), 2: an entry (a near-plane face facing the light), −1: the wrong way round,
// 0: edge-on within rounding. Moving a corner by δ changes the projected area by at most δ/2 times
// the opposite edge as projected along f: walls parallel to f, however tall, stay within rounding
// of zero.
inline int side_along(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& f, double area,
                      bool source, double ulp_tol) {
  const auto across = [&](const Vec3d& e) { return length(e - dot(e, f) * f); };
  const double tol = ulp_tol * (across(b - a) + across(c - b) + across(a - c));
  if (area > tol) return source ? -1 : 1;
  if (area < -tol) return source ? 2 : -1;
  return 0;
}

}  // namespace lightvol
