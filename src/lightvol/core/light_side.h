// Which side of a face a light sees, beyond what float rounding of its corners could change: the
// test the proof from the light (check/light_proof.cpp) makes of every face, and the float32 guard
// (volume/float32_guard.cpp) of the faces it cannot settle more cheaply. Both judge a face with
// the motion of its own corners (corner_motion): nothing else in the mesh widens it.
#pragma once

#include <algorithm>
#include <cmath>

#include <lightvol/core/math.h>

namespace lightvol {

// How far float32 storage may have moved the corners of face (a, b, c) (absolute coordinates):
// eight float ulps of the largest |coordinate| among its own corners (storage rounds each by half
// an ulp; the rest is room for the arithmetic that made them). Only the face's own corners count:
// a far vertex elsewhere in the mesh, used or not, gives this face no slack.
inline double corner_motion(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const auto largest = [](const Vec3d& p) {
    return std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)});
  };
  // × 2^-23 as a product: what std::ldexp(x, -23) gives, to the bit (both round x · 2^-23 once,
  // to nearest), without ldexp's call into libm on every face.
  return 8 * (std::max({largest(a), largest(b), largest(c)}) * 0x1p-23);
}

// How far the arithmetic that places a point relative to the light (differences from the eye or
// the near plane's origin, in double) may move it: a few double ulps of the largest |coordinate|
// of `p`, the light's position or origin. Negligible beside float rounding unless the light is
// far larger than the faces' coordinates.
inline double frame_motion(const Vec3d& p) {
  return std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}) * 0x1p-48;  // ldexp(x, -48)
}

// A point light: `a`, `b`, `c` are the face's corners relative to the eye, `bc` = b × c and
// `det` = a · bc. +1: the light sees the face from behind (it faces away), −1: the face faces the
// light, 0: edge-on, |det| within what moving each corner by `motion` could change.
inline int side_from_point(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& bc,
                           double det, double motion) {
  const double tol = motion * (length(bc) + length(cross(c, a)) + length(cross(a, b)));
  if (det > tol) return 1;
  if (det < -tol) return -1;
  return 0;
}

// A directional light along the unit vector `f`: `area` is the face's projected area,
// 0.5 (b − a) × (c − a) · f, and `source` whether all three corners lie on the near plane. +1: an
// exit (facing along f), 2: an entry (a near-plane face facing the light), −1: the wrong way round,
// 0: edge-on within moving each corner by `motion`. Moving a corner by δ changes the projected area
// by at most δ/2 times the opposite edge as projected along f: walls parallel to f, however tall,
// stay within rounding of zero.
inline int side_along(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& f, double area,
                      bool source, double motion) {
  const auto across = [&](const Vec3d& e) { return length(e - dot(e, f) * f); };
  const double tol = motion * (across(b - a) + across(c - b) + across(a - c));
  if (area > tol) return source ? -1 : 1;
  if (area < -tol) return source ? 2 : -1;
  return 0;
}

}  // namespace lightvol
