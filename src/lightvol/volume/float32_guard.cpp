#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <lightvol/core/buffer.h>
#include <lightvol/volume/detail/float32_guard.h>
#include <lightvol/volume/float32_guard.h>

namespace lightvol {
namespace detail {

GuardLight guard_light(const Light& light, Space space) {
  const Light frame = light_in_space(light, space);
  GuardLight g;
  g.type = light.type;
  g.position = frame.position;
  if (light.type == LightType::directional) {
    g.f = normalize(frame.direction);
    g.near_origin = g.position + light.near * g.f;
  }
  g.at_light = 4 * std::ldexp(std::max({std::abs(g.position.x), std::abs(g.position.y),
                                        std::abs(g.position.z),
                                        static_cast<double>(std::numeric_limits<float>::min())}),
                              -23);
  return g;
}

// The tally of `n` vertices (x y z floats from `xyz`), in parallel.
VertexTally tally_vertices(const float* xyz, std::size_t n, const GuardLight& g) {
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, n, std::size_t{1} << 14), VertexTally{},
      [&](const tbb::blocked_range<std::size_t>& r, VertexTally acc) {
        acc.add(xyz + 3 * r.begin(), r.size(), g);
        return acc;
      },
      [](VertexTally a, const VertexTally& b) {
        a.merge(b);
        return a;
      });
}

namespace {

std::string shown(double x) {
  std::ostringstream out;
  out << x;
  return out.str();
}

std::string frustum_keys(const Light& light) {
  return light.type == LightType::spot   ? "keys 'near', 'far' and 'fov_y_deg'"
         : light.type == LightType::omni ? "keys 'near' and 'far'"
                                         : "keys 'ortho', 'near' and 'far'";
}

}  // namespace

Status vertex_verdict(const VertexTally& vertices, const Light& light,
                      const std::string& light_source) {
  constexpr double kLargest = 1e18;  // squares stay below float's 3.4e38
  if (!vertices.finite)
    return Error{light_source + ": " + frustum_keys(light) +
                     ": the volume's vertices are not finite numbers (near " + shown(light.near) +
                     ", far " + shown(light.far) +
                     ": more than double precision holds); bring far closer to near",
                 ErrorKind::unrepresentable};
  if (vertices.largest > kLargest)
    return Error{light_source + ": " + frustum_keys(light) + ": the volume reaches coordinate " +
                     shown(vertices.largest) + "; float32 meshes need coordinates below " +
                     shown(kLargest) + " (choose the scene's units so that the frustum is smaller)",
                 ErrorKind::unrepresentable};
  const Vec3d span = vertices.hi - vertices.lo;
  const double across = std::max({span.x, span.y, span.z});
  // The checks form areas and volumes in float: a volume smaller than this underflows them.
  constexpr double kSmallest = 1e-12;
  if (across < kSmallest)
    return Error{light_source + ": " + frustum_keys(light) + ": the volume is " + shown(across) +
                     " across; float32 meshes and their checks need at least " + shown(kSmallest) +
                     " (choose the scene's units, or near and far, so that it is larger)",
                 ErrorKind::unrepresentable};
  return {};
}

Status representable_verdict(const VertexTally& vertices, const FaceTally& faces,
                             const Light& light, Space space, const std::string& light_source) {
  if (Status s = vertex_verdict(vertices, light, light_source); !s) return s;
  const double largest = vertices.largest;
  // The float step judged against a texel is that of the largest coordinate, the light's
  // position's included: a directional light far behind its near plane is refused however small
  // the volume's own coordinates are (where its faces would be placed is as coarse as that).
  const GuardLight guard = guard_light(light, space);
  const double light_largest = std::max(
      {std::abs(guard.position.x), std::abs(guard.position.y), std::abs(guard.position.z)});
  const double max_abs = std::max(largest, light_largest);
  // Faces the proof accepts may still be too fine for float32 to place where they belong, which
  // the apex's cone and the proof's sums then notice: float steps at those coordinates against the
  // spacing of the faces across the light's rays, about a texel (the light's field over the square
  // root of the vertex count per map). Point lights: the angle a step subtends at the vertex
  // nearest the light against a texel's angle; directional: the step against a texel's width in
  // the ortho extents. Steps coarser than a sixteenth of that refuse the volume (a spot far from
  // the origin, a fov of 1e-6 degrees); a thin but wide box (8193 wide, 1 deep) is fine.
  const double step = max_abs * std::numeric_limits<float>::epsilon();
  const double maps = light.type == LightType::omni ? double(kOmniFaces) : 1.0;
  const double texels_across = std::sqrt(std::max(1.0, double(vertices.vertices) / maps));
  const double px = std::abs(light.projection(0, 0)), py = std::abs(light.projection(1, 1));
  double ratio = 0;  // a float step over a texel's spacing
  if (light.type == LightType::directional) {
    ratio = step / (std::min(2 / px, 2 / py) / texels_across);
  } else if (std::isfinite(vertices.nearest2)) {
    const double field = light.type == LightType::omni
                             ? std::numbers::pi / 2
                             : std::min(2 * std::atan(1 / px), 2 * std::atan(1 / py));
    ratio = (step / std::sqrt(vertices.nearest2)) / (field / texels_across);
  }
  const bool coarse = ratio > 1.0 / 16;
  if (faces.collapsed == 0 && faces.turned == 0 && !coarse) return {};
  const Vec3d extent = vertices.hi - vertices.lo;
  const double size = std::max({extent.x, extent.y, extent.z});
  std::string what =
      light_source + ": float32 cannot hold this volume (coordinates up to " + shown(largest) +
      (light_largest > largest ? ", the light's position up to " + shown(light_largest)
                               : std::string()) +
      ", steps of " + shown(step) + ", " + shown(ratio) + " of a texel's spacing; " +
      std::to_string(faces.collapsed) + " of " + std::to_string(faces.triangles) +
      " faces collapse to zero area, " + std::to_string(faces.turned) + " face the light)";

  // A directional light's volume begins `near` from its position, in either frame: far for the
  // volume's size, only moving the position closer helps.
  if (light.type == LightType::directional && light.near > 100 * size)
    return Error{
        what + ": keys 'position' and 'near': the volume begins " + shown(light.near) +
            " from the light's position, far for its size " + shown(size) +
            "; move the position along the light's direction towards the volume and reduce "
            "near and far by as much",
        ErrorKind::unrepresentable};
  if (space == Space::world && largest > 100 * size)
    return Error{
        what + ": key 'position': the light is far from the origin for the volume's size " +
            shown(size) +
            "; write it in the light's eye space with VolumeOptions::space = Space::light and "
            "place it with the light's view matrix",
        ErrorKind::unrepresentable};
  return Error{
      what + ": " + frustum_keys(light) +
          ": the frustum is too thin, or far/near too large, for float32; widen it or bring "
          "near and far closer",
      ErrorKind::unrepresentable};
}

namespace {

// The held mesh's faces are judged kLanes at a time: a loop without branches, which the compiler
// vectorizes, finds the faces judge_face settles first (collapsed: a zero normal; sound: seen
// from behind by FaceJudge::away, for point lights); judge_face judges the rest again. The same
// expressions, term for term, as judge_face's (this file is compiled without contraction into
// fused multiply-adds, so the vector versions for wider instruction sets round as it does).
constexpr std::size_t kLanes = 256;

// For faces [0, n) of `tri`: 1 in `collapsed` for a zero normal, 1 in `away` for a face whose
// eye-relative determinant is not negative.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
[[gnu::target_clones("avx512f", "avx2", "default")]]
#endif
[[gnu::noinline]] void
settle_lanes(const std::uint32_t* tri, const float* p, std::size_t n, Vec3d eye, double* collapsed,
             double* away) {
#pragma omp simd
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t ia = 3 * std::size_t{tri[3 * i]}, ib = 3 * std::size_t{tri[3 * i + 1]},
                      ic = 3 * std::size_t{tri[3 * i + 2]};
    const double ax = p[ia], ay = p[ia + 1], az = p[ia + 2];
    const double bx = p[ib], by = p[ib + 1], bz = p[ib + 2];
    const double cx = p[ic], cy = p[ic + 1], cz = p[ic + 2];
    const double ux = bx - ax, uy = by - ay, uz = bz - az;
    const double vx = cx - ax, vy = cy - ay, vz = cz - az;
    const double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
    collapsed[i] = ((nx == 0) & (ny == 0) & (nz == 0)) ? 1.0 : 0.0;
    const double ex = ax - eye.x, ey = ay - eye.y, ez = az - eye.z;
    away[i] = (ex * nx + ey * ny + ez * nz >= 0) ? 1.0 : 0.0;
  }
}

}  // namespace

FaceTally tally_faces(const Mesh& mesh, const FaceJudge& judge, bool lanes) {
  const float* p = mesh.positions.data();
  const bool point = judge.type != LightType::directional;
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, mesh.num_triangles(), std::size_t{1} << 14), FaceTally{},
      [&](const tbb::blocked_range<std::size_t>& r, FaceTally acc) {
        const std::uint32_t* first = mesh.indices.data() + 3 * r.begin();
        const auto corners = [&](std::size_t t, int k) {
          return p + 3 * std::size_t{first[3 * t + k]};
        };
        if (!point || !lanes || !vector_lanes()) {
          acc.add(r.size(), corners, judge);
          return acc;
        }
        double collapsed[kLanes], away[kLanes];
        std::uint64_t c = 0, turned = 0;
        for (std::size_t lane0 = 0; lane0 < r.size(); lane0 += kLanes) {
          const std::size_t n = std::min(kLanes, r.size() - lane0);
          settle_lanes(first + 3 * lane0, p, n, judge.eye, collapsed, away);
          for (std::size_t i = 0; i < n; ++i) {
            if (collapsed[i] != 0) {
              ++c;
            } else if (away[i] == 0) {
              const FaceFinding found = judge_face(corners(lane0 + i, 0), corners(lane0 + i, 1),
                                                   corners(lane0 + i, 2), judge);
              c += found == FaceFinding::collapsed;
              turned += found == FaceFinding::turned;
            }
          }
        }
        acc.triangles += r.size(), acc.collapsed += c, acc.turned += turned;
        return acc;
      },
      [](FaceTally a, const FaceTally& b) {
        a.merge(b);
        return a;
      });
}

}  // namespace detail

Status check_representable(const Mesh& mesh, const Light& light, Space space,
                           const std::string& light_source) {
  using namespace detail;  // NOLINT(google-build-using-namespace): the guard's own passes
  const GuardLight guard = guard_light(light, space);
  const VertexTally vertices = tally_vertices(mesh.positions.data(), mesh.num_vertices(), guard);
  if (Status s = vertex_verdict(vertices, light, light_source); !s) return s;
  const FaceTally faces = tally_faces(mesh, FaceJudge(vertices, guard));
  return representable_verdict(vertices, faces, light, space, light_source);
}

}  // namespace lightvol
