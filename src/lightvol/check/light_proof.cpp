// The light's non-self-nesting proof: every triangle seen from the light with the same
// orientation, and the per-triangle solid angles (point light) or projected areas (directional)
// adding up to what a single crossing needs.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <unordered_map>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <lightvol/check/detail/linear_checks.h>

namespace lightvol {
namespace detail {
namespace {

constexpr double kPi = std::numbers::pi;

// Per-triangle sums of the light proof.
struct LightSums {
  double positive = 0;  // Σ of the contributions counted
  double negative = 0;  // Σ |contribution| of faces on the wrong side (offenders)
  double source = 0;    // directional: Σ |area| of near-plane faces facing the light
  double zeroed = 0;    // Σ |contribution| of faces counted as edge-on
  std::uint64_t wrong = 0;
  LightSums operator+(const LightSums& o) const {
    return {positive + o.positive, negative + o.negative, source + o.source, zeroed + o.zeroed,
            wrong + o.wrong};
  }
};

// Solid angle of the cone at `apex` bounded by the faces incident to vertex `apex_vertex`, on the
// side those faces' outward normals point away from: by Gauss–Bonnet, 2π + the sum of the
// signed turning angles of the link polygon (the edges opposite the apex, in face order) on the
// unit sphere. Returns a negative value when the link is not one simple loop.
double apex_cone_solid_angle(const Mesh& mesh, std::uint32_t apex_vertex, Vec3d apex) {
  std::unordered_map<std::uint32_t, std::uint32_t> next;
  for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
    const auto tri = mesh.triangle(t);
    for (int k = 0; k < 3; ++k) {
      if (tri[k] != apex_vertex) continue;
      if (!next.emplace(tri[(k + 1) % 3], tri[(k + 2) % 3]).second) return -1;
    }
  }
  if (next.size() < 3) return -1;
  std::vector<Vec3d> loop;
  std::uint32_t v = next.begin()->first;
  for (std::size_t k = 0; k < next.size(); ++k) {
    loop.push_back(normalize(position(mesh, v) - apex));
    const auto it = next.find(v);
    if (it == next.end()) return -1;
    v = it->second;
  }
  if (v != next.begin()->first) return -1;
  const std::size_t n = loop.size();
  double turning = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3d prev = loop[(i + n - 1) % n], u = loop[i], nxt = loop[(i + 1) % n];
    const Vec3d t_in = (dot(prev, u) * u) - prev;
    const Vec3d t_out = nxt - (dot(nxt, u) * u);
    turning += std::atan2(dot(cross(t_in, t_out), u), dot(t_in, t_out));
  }
  return 2 * kPi + turning;
}

}  // namespace

namespace {

// The mesh's vertex at the light, if any: "at the light" means within the rounding of
// coordinates there (a few float ulps of the light's own position), not of the largest
// coordinate: a spot volume's near plane can lie 10^-6 of the far distance from its apex.
// Quantized positions are only known to within their step (`quantum`).
struct LightVertices {
  std::vector<std::uint32_t> at_light;  // all the vertices within the tolerance
  double offset = 0;                    // of the last of them from the light, max-norm
  double light_ulp = 0;                 // a float ulp of the light position's largest coordinate
};

LightVertices vertices_at_light(const Mesh& mesh, const Vec3d& light_pos, double quantum) {
  LightVertices out;
  out.light_ulp =
      std::ldexp(std::max({std::abs(light_pos.x), std::abs(light_pos.y), std::abs(light_pos.z),
                           static_cast<double>(std::numeric_limits<float>::min())}),
                 -23);
  const double at_light_tol = std::max(4 * out.light_ulp, quantum);
  for (std::size_t v = 0; v < mesh.num_vertices(); ++v) {
    const Vec3d d = position(mesh, static_cast<std::uint32_t>(v)) - light_pos;
    const double offset = std::max({std::abs(d.x), std::abs(d.y), std::abs(d.z)});
    if (offset <= at_light_tol) {
      out.at_light.push_back(static_cast<std::uint32_t>(v));
      out.offset = offset;
    }
  }
  return out;
}

// Van Oosterom–Strackee: tan(Ω/2) = a·(b×c) / (|a||b||c| + (a·b)|c| + (a·c)|b| + (b·c)|a|).
// The sign of det = a·(b×c) says which side the light at `eye` sees (+1 away, −1 facing it, 0
// edge-on or a face of the apex vertex `apex`); |det| within what moving each vertex by `ulp_tol`
// could change counts as edge-on. `*omega` is the signed solid angle.
int classify_from_point(const Mesh& mesh, std::size_t t, const Vec3d& eye, std::uint32_t apex,
                        double ulp_tol, double* omega) {
  const auto [ia, ib, ic] = mesh.triangle(t);
  if (ia == apex || ib == apex || ic == apex) {
    *omega = 0;
    return 0;
  }
  const Vec3d a = position(mesh, ia) - eye, b = position(mesh, ib) - eye,
              c = position(mesh, ic) - eye;
  const Vec3d bc = cross(b, c);
  const double det = dot(a, bc);
  const double la = length(a), lb = length(b), lc = length(c);
  const double denom = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
  *omega = 2 * std::atan2(det, denom);
  const double tol = ulp_tol * (length(bc) + length(cross(c, a)) + length(cross(a, b)));
  if (det > tol) return 1;
  if (det < -tol) return -1;
  return 0;
}

// The solid angles of all faces seen from `eye`, summed by side, in parallel (deterministic).
LightSums solid_angle_sums(const Mesh& mesh, const Vec3d& eye, std::uint32_t apex, double ulp_tol) {
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<std::size_t>(0, mesh.num_triangles(), 1 << 14), LightSums{},
      [&](const tbb::blocked_range<std::size_t>& range, LightSums s) {
        for (std::size_t t = range.begin(); t != range.end(); ++t) {
          double omega = 0;
          const int side = classify_from_point(mesh, t, eye, apex, ulp_tol, &omega);
          if (side > 0) {
            s.positive += omega;
          } else if (side < 0) {
            s.negative -= omega;
            ++s.wrong;
          } else {
            s.zeroed += std::abs(omega);
          }
        }
        return s;
      },
      [](const LightSums& x, const LightSums& y) { return x + y; });
}

}  // namespace

CheckResult nesting_check_point(const Mesh& mesh, const Light& light, double eps_pos,
                                double quantum, int max_offenders, CheckReport* report) {
  CheckResult r;
  r.name = kCheckNesting;
  report->proof = NestingProof::solid_angles;
  // The light at a vertex (a spot volume's apex): view from that vertex's exact position, so the
  // faces around it are exactly degenerate and the cone is measured from the same point.
  const Vec3d light_pos = light.position;
  const LightVertices found = vertices_at_light(mesh, light_pos, quantum);
  const std::vector<std::uint32_t>& at_light = found.at_light;
  const double light_ulp = found.light_ulp, light_offset = found.offset;
  if (at_light.size() > 1) {
    r.status = CheckStatus::failed;
    r.count = at_light.size();
    r.detail = std::to_string(at_light.size()) + " vertices lie at the light position";
    for (std::uint32_t v : at_light)
      if (r.offenders.size() < static_cast<std::size_t>(max_offenders))
        r.offenders.push_back(make_offender(mesh, {}, {v}));
    return r;
  }
  const bool at_vertex = !at_light.empty();
  const Vec3d eye = at_vertex ? position(mesh, at_light.front()) : light_pos;
  const std::uint32_t apex = at_vertex ? at_light.front() : ~0u;
  const double ulp_tol = 8 * eps_pos + quantum;

  const std::size_t nt = mesh.num_triangles();
  const LightSums sums = solid_angle_sums(mesh, eye, apex, ulp_tol);
  if (sums.wrong > 0) {
    for (std::size_t t = 0; t < nt && r.offenders.size() < static_cast<std::size_t>(max_offenders);
         ++t) {
      double omega = 0;
      if (classify_from_point(mesh, t, eye, apex, ulp_tol, &omega) < 0)
        r.offenders.push_back(face_offender(mesh, t));
    }
  }

  double expected = 4 * kPi;
  std::string where = "the light inside";
  if (at_vertex) {
    expected = apex_cone_solid_angle(mesh, apex, eye);
    where = "the light at vertex " + std::to_string(apex);
    if (light_offset > 4 * light_ulp) {
      std::ostringstream off;
      off.precision(3);
      off << " (" << light_offset << " from it, within the positions' quantization step " << quantum
          << ")";
      where += off.str();
    }
    if (expected < 0) {
      r.status = CheckStatus::failed;
      r.count = 1;
      r.detail = "the faces around the light's vertex " + std::to_string(apex) +
                 " do not form one simple cone";
      r.offenders.insert(r.offenders.begin(), make_offender(mesh, {}, {apex}));
      return r;
    }
  }
  const double sum = sums.positive - sums.negative;
  report->light_sum = sum;
  report->light_expected = expected;
  const double slack = sums.zeroed + 1e-7 * (std::abs(expected) + std::abs(sum) + 1e-3);
  const bool sum_ok = std::abs(sum - expected) <= slack;
  r.count = sums.wrong;
  std::ostringstream detail;
  detail.precision(9);
  if (sums.wrong > 0) detail << sums.wrong << " faces face the light (negative solid angle); ";
  detail << "solid angles sum to " << sum << " sr, " << (sum_ok ? "as" : "but") << " " << where
         << " needs " << expected << " sr";
  if (!sum_ok) {
    detail << " (difference " << sum - expected << "): ";
    detail << (std::abs(sum) < 1e-6 ? "the light is outside the volume"
                                    : "some directions are covered more than once or not at all");
  }
  r.detail = detail.str();
  r.status = sums.wrong == 0 && sum_ok ? CheckStatus::passed : CheckStatus::failed;
  if (!sum_ok && r.count == 0) r.count = 1;
  return r;
}

CheckResult nesting_check_directional(const Mesh& mesh, const Light& light, double eps_pos,
                                      double quantum, int max_offenders, CheckReport* report) {
  CheckResult r;
  r.name = kCheckNesting;
  report->proof = NestingProof::projected_areas;
  const Vec3d f = normalize(light.direction), origin = light.position + light.near * f;
  const double plane_tol = 8 * eps_pos + quantum, ulp_tol = 8 * eps_pos + quantum;
  const auto on_near_plane = [&](std::uint32_t v) {
    return std::abs(dot(position(mesh, v) - origin, f)) <= plane_tol;
  };
  // Returns +1 (an exit: normal along f), −1 (a face on the wrong side), 0 (edge-on), or 2 (an
  // entry: a near-plane face facing the light); `area` is the signed projected area.
  const auto classify = [&](std::size_t t, double* area) -> int {
    const auto [ia, ib, ic] = mesh.triangle(t);
    const Vec3d a = position(mesh, ia), b = position(mesh, ib), c = position(mesh, ic);
    *area = 0.5 * dot(cross(b - a, c - a), f);
    // Moving a vertex by δ changes the projected area by at most δ/2 times the opposite edge as
    // projected along f: walls parallel to f, however tall, stay within rounding of zero.
    const auto across = [&](const Vec3d& e) { return length(e - dot(e, f) * f); };
    const double tol = ulp_tol * (across(b - a) + across(c - b) + across(a - c));
    const bool source = on_near_plane(ia) && on_near_plane(ib) && on_near_plane(ic);
    if (*area > tol) return source ? -1 : 1;
    if (*area < -tol) return source ? 2 : -1;
    return 0;
  };
  const std::size_t nt = mesh.num_triangles();
  const LightSums sums = tbb::parallel_deterministic_reduce(
      tbb::blocked_range<std::size_t>(0, nt, 1 << 14), LightSums{},
      [&](const tbb::blocked_range<std::size_t>& range, LightSums s) {
        for (std::size_t t = range.begin(); t != range.end(); ++t) {
          double area = 0;
          switch (classify(t, &area)) {
            case 1:
              s.positive += area;
              break;
            case 2:
              s.source -= area;
              break;
            case -1:
              s.negative += std::abs(area), ++s.wrong;
              break;
            default:
              s.zeroed += std::abs(area);
              break;
          }
        }
        return s;
      },
      [](const LightSums& x, const LightSums& y) { return x + y; });
  if (sums.wrong > 0) {
    for (std::size_t t = 0; t < nt && r.offenders.size() < static_cast<std::size_t>(max_offenders);
         ++t) {
      double area = 0;
      if (classify(t, &area) == -1) r.offenders.push_back(face_offender(mesh, t));
    }
  }
  report->light_sum = sums.positive;
  report->light_expected = sums.source;
  const double slack = sums.zeroed + sums.negative + 1e-7 * (sums.positive + sums.source + 1e-9);
  const bool sum_ok = sums.source > 0 && std::abs(sums.positive - sums.source) <= slack;
  r.count = sums.wrong + (sum_ok ? 0 : 1);
  std::ostringstream detail;
  detail.precision(9);
  if (sums.wrong > 0)
    detail << sums.wrong << " faces are seen from the wrong side along the light direction; ";
  detail << "projected exit area " << sums.positive << ", entry area on the near plane "
         << sums.source;
  if (sums.source <= 0)
    detail << ": no face lies in the light's near plane facing the light";
  else if (!sum_ok)
    detail << ": they differ, some rays cross the volume more than once";
  r.detail = detail.str();
  r.status = sums.wrong == 0 && sum_ok ? CheckStatus::passed : CheckStatus::failed;
  return r;
}

}  // namespace detail

Light light_in_space(const Light& light, Space space) {
  if (space == Space::world) return light;
  Light out = light;
  out.position = {0, 0, 0};
  // Omni light space keeps world axes; spot and directional look down their eye space's −Z.
  if (light.type != LightType::omni) out.direction = {0, 0, -1};
  return out;
}

}  // namespace lightvol
