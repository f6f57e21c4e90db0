// The float32 guard's two passes (check_representable, volume/float32_guard.h), shared by the held
// volume's guard (float32_guard.cpp) and the streamed static volume's (StaticVolumeStream, which
// tallies its rows as it makes them). Internal to the volume stage.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>

#include <lightvol/core/light_side.h>
#include <lightvol/core/math.h>
#include <lightvol/core/result.h>
#include <lightvol/light/light.h>
#include <lightvol/volume/static_volume.h>

namespace lightvol::detail {

// The float32 guard (check_representable) judges a volume as check_volume_linear's proof from the
// light would: in the volume's frame (world, or the light's eye space with the light at the origin,
// spot and directional looking down −Z), with its tolerance, each face's own corner motion (eight
// float ulps of its corners' largest coordinate, core/light_side.h). The vertex at the light is
// known only after every vertex, so the guard runs in two passes,
// each a tally gathered vertex by vertex or face by face and merged in any order (maxima, minima
// and counts: the same numbers however the work is split): first the vertices (VertexTally), then
// the faces judged with what the vertices said (FaceJudge, FaceTally). A held mesh is read twice;
// StaticVolumeStream makes its rows twice. Both give the same verdict and message.

// The light as the guard sees it, in the volume's frame.
struct GuardLight {
  LightType type = LightType::spot;
  Vec3d position;       // the light's position in the frame
  Vec3d f;              // directional: the unit direction
  Vec3d near_origin;    // directional: a point of the near plane
  double at_light = 0;  // point lights: a vertex this close (max-norm) is at the light (4 ulps)
};

// The guard's light for `light`'s volume built in `space`.
GuardLight guard_light(const Light& light, Space space);

// The first pass: the vertices.
struct VertexTally {
  bool finite = true;
  double largest = 0;  // the largest |coordinate|
  Vec3d lo{std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
           std::numeric_limits<double>::max()};
  Vec3d hi{-std::numeric_limits<double>::max(), -std::numeric_limits<double>::max(),
           -std::numeric_limits<double>::max()};
  std::uint64_t vertices = 0;
  // Point lights: the vertices at the light (a spot volume's apex) and one of them (the one, when
  // there is one), and the squared distance from the light of the nearest other vertex.
  std::uint64_t at_light = 0;
  Vec3d apex;
  double nearest2 = std::numeric_limits<double>::infinity();

  // Adds `n` vertices (x y z floats from `xyz`), in locals the compiler keeps in registers:
  // branch-free but for the vertices at the light (the rest is of no use once a coordinate is not
  // finite: the verdict then says only that).
  void add(const float* xyz, std::size_t n, const GuardLight& g) {
    constexpr double kMax = std::numeric_limits<double>::max();
    const bool point = g.type != LightType::directional;
    bool all_finite = true;
    double big = largest, near2 = nearest2;
    double lx = lo.x, ly = lo.y, lz = lo.z, hx = hi.x, hy = hi.y, hz = hi.z;
    for (std::size_t v = 0; v < n; ++v) {
      const float* q = xyz + 3 * v;
      const double x = q[0], y = q[1], z = q[2];
      const double ax = std::abs(x), ay = std::abs(y), az = std::abs(z);
      all_finite &= ax <= kMax && ay <= kMax && az <= kMax;  // false for NaN too
      big = std::max(big, std::max(ax, std::max(ay, az)));
      lx = std::min(lx, x), ly = std::min(ly, y), lz = std::min(lz, z);
      hx = std::max(hx, x), hy = std::max(hy, y), hz = std::max(hz, z);
      if (!point) continue;
      const double dx = x - g.position.x, dy = y - g.position.y, dz = z - g.position.z;
      if (std::max(std::abs(dx), std::max(std::abs(dy), std::abs(dz))) <= g.at_light) {
        ++at_light;
        apex = {x, y, z};
      } else {
        near2 = std::min(near2, dx * dx + dy * dy + dz * dz);
      }
    }
    vertices += n;
    finite = finite && all_finite;
    largest = big, nearest2 = near2;
    lo = {lx, ly, lz}, hi = {hx, hy, hz};
  }
  void merge(const VertexTally& o) {
    finite = finite && o.finite;
    largest = std::max(largest, o.largest);
    lo = {std::min(lo.x, o.lo.x), std::min(lo.y, o.lo.y), std::min(lo.z, o.lo.z)};
    hi = {std::max(hi.x, o.hi.x), std::max(hi.y, o.hi.y), std::max(hi.z, o.hi.z)};
    vertices += o.vertices;
    if (o.at_light > 0) apex = o.apex;
    at_light += o.at_light;
    nearest2 = std::min(nearest2, o.nearest2);
  }
};

// The tally of `n` vertices (x y z floats from `xyz`), in parallel.
VertexTally tally_vertices(const float* xyz, std::size_t n, const GuardLight& g);

// How the second pass judges a face: turned towards the light, as the light proof of
// check_volume_linear decides it (check/light_proof.cpp), beyond what moving each vertex by `tol`
// could do. Point lights: the determinant of the face seen from the eye; directional: the face's
// area projected along the light, exits facing along it, the near plane's faces against it.
struct FaceJudge {
  LightType type = LightType::spot;
  Vec3d eye;  // point lights: the vertex at the light if there is exactly one, else the light
  Vec3d f, near_origin;
  double extra = 0;  // the rounding of the frame's own arithmetic (frame_motion), as the proof's

  FaceJudge(const VertexTally& v, const GuardLight& g)
      : type(g.type),
        eye(v.at_light == 1 ? v.apex : g.position),
        f(g.f),
        near_origin(g.near_origin),
        extra(g.type == LightType::directional
                  ? std::max(frame_motion(g.near_origin), frame_motion(g.position))
                  : frame_motion(eye)) {}

  // Whether face (a, b, c), of normal n = (b − a) × (c − a) (not zero), surely faces the right
  // way, from a test cheap enough for every face: nearly all of them pass it. Point lights:
  // det(a − eye, b − eye, c − eye) is (a − eye)·n, and a face where that is not negative faces
  // away (rounding moves it by some 1e-16 of its terms, the tolerance is 1e-6 of them: they could
  // only disagree for faces a billionth of a radian across, which the texel test of the verdict
  // refuses anyway). Directional: a face with a vertex off the near plane (beyond the face's
  // motion `tol`) is an exit, which faces the right way when its projected area is not negative.
  bool away(const Vec3d& a, const Vec3d& n, double tol) const {
    if (type == LightType::directional)
      return std::abs(dot(a - near_origin, f)) > tol && dot(n, f) >= 0;
    return dot(a - eye, n) >= 0;
  }

  // Whether face (a, b, c), of normal n = (b − a) × (c − a) (not zero), faces the wrong way: the
  // proof's own test (core/light_side.h), with the face's motion `tol`. A face of the vertex at
  // the eye has det 0 exactly: the proof leaves the apex's faces out.
  [[gnu::noinline]] bool turned(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& n,
                                double tol) const {
    if (type == LightType::directional) {
      const auto on_near_plane = [&](const Vec3d& p) {
        return std::abs(dot(p - near_origin, f)) <= tol;
      };
      const bool source = on_near_plane(a) && on_near_plane(b) && on_near_plane(c);
      return side_along(a, b, c, f, 0.5 * dot(n, f), source, tol) == -1;
    }
    const Vec3d pa = a - eye, pb = b - eye, pc = c - eye;
    const Vec3d bc = cross(pb, pc);
    return side_from_point(pa, pb, pc, bc, dot(pa, bc), tol) == -1;
  }
};

// What the second pass finds of a face of float corners `qa`, `qb`, `qc`.
enum class FaceFinding { sound, collapsed, turned };
inline FaceFinding judge_face(const float* qa, const float* qb, const float* qc,
                              const FaceJudge& judge) {
  const Vec3d a{qa[0], qa[1], qa[2]}, b{qb[0], qb[1], qb[2]}, c{qc[0], qc[1], qc[2]};
  const Vec3d n = cross(b - a, c - a);
  if (n.x == 0 && n.y == 0 && n.z == 0) return FaceFinding::collapsed;
  const double tol = corner_motion(a, b, c) + judge.extra;
  if (judge.away(a, n, tol) || !judge.turned(a, b, c, n, tol)) return FaceFinding::sound;
  return FaceFinding::turned;
}

// The second pass: the faces.
struct FaceTally {
  std::uint64_t triangles = 0, collapsed = 0, turned = 0;

  // Adds faces [0, n); corners(t, k) points to the x y z floats of corner k of face t. Counts in
  // locals the compiler keeps in registers.
  template <class Corners>
  void add(std::size_t n, const Corners& corners, const FaceJudge& judge) {
    std::uint64_t c = 0, t = 0;
    for (std::size_t f = 0; f < n; ++f) {
      const FaceFinding found = judge_face(corners(f, 0), corners(f, 1), corners(f, 2), judge);
      c += found == FaceFinding::collapsed;
      t += found == FaceFinding::turned;
    }
    triangles += n, collapsed += c, turned += t;
  }
  void merge(const FaceTally& o) {
    triangles += o.triangles;
    collapsed += o.collapsed;
    turned += o.turned;
  }
};

// The second pass over a held mesh, in parallel: point lights' faces are first settled in
// vectorized lanes (collapsed, or facing away) where vector_lanes() (core/buffer.h), the rest
// judged one by one; with `lanes` false, every face one by one (the same counts: the tests compare
// the two) (float32_guard.cpp).
FaceTally tally_faces(const Mesh& mesh, const FaceJudge& judge, bool lanes = true);

// Refusals the vertices decide alone: not finite, too large, too small.
Status vertex_verdict(const VertexTally& vertices, const Light& light,
                      const std::string& light_source);
// The whole verdict (vertex_verdict's first).
Status representable_verdict(const VertexTally& vertices, const FaceTally& faces,
                             const Light& light, Space space, const std::string& light_source);

// build_static_volume without the guard: the volume as the grid and closing make it, for what
// judges it (the guard's tests need the volumes it refuses). `storage`: as build_static_volume's.
Result<Mesh> assemble_static_volume(const Light& light, const DepthImage& depth,
                                    const VolumeOptions& options, const std::string& source,
                                    Mesh storage = {});

}  // namespace lightvol::detail
