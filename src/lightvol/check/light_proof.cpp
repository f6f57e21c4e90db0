// The light's non-self-nesting proof: every triangle seen from the light with the same
// orientation, and the per-triangle solid angles (point light) or projected areas (directional)
// adding up to what a single crossing needs.
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <sstream>
#include <unordered_map>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <lightvol/check/detail/linear_checks.h>
#include <lightvol/core/buffer.h>
#include <lightvol/core/light_side.h>

namespace lightvol {
namespace detail {
namespace {

constexpr double kPi = std::numbers::pi;

// Solid angle of the cone at `apex` bounded by the faces incident to vertex `apex_vertex`, on the
// side those faces' outward normals point away from: by Gauss–Bonnet, 2π + the sum of the
// signed turning angles of the link polygon (the edges opposite the apex, in face order) on the
// unit sphere. Returns a negative value when the link is not one simple loop.
double apex_cone_solid_angle(const Mesh& mesh,
                             const std::vector<std::pair<std::uint32_t, std::uint32_t>>& link,
                             Vec3d apex) {
  std::unordered_map<std::uint32_t, std::uint32_t> next;
  for (const auto& [from, to] : link)
    if (!next.emplace(from, to).second) return -1;
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

// atan2(y, x), by its series for a small angle in the right half-plane (a face of a fine grid
// subtends 10^-8 sr; the terms left out are below 10^-18 of it): within an ulp of std::atan2,
// and a few times faster.
double small_atan2(double y, double x) {
  if (!(x > 0 && std::abs(y) <= 1e-3 * x)) return std::atan2(y, x);
  const double r = y / x, r2 = r * r;
  return r * (1 - r2 * (1.0 / 3 - r2 * (1.0 / 5)));
}

// The distances from the eye of the vertices [first, first + size): a face's three vertices are
// each shared by about six faces, so a block of faces computes them once per vertex.
struct NearDistances {
  const double* distance = nullptr;
  std::uint32_t first = 0, size = 0;
  double of(std::uint32_t v, const Vec3d& from_eye) const {
    return v - first < size ? distance[v - first] : length(from_eye);
  }
};

// Van Oosterom–Strackee: tan(Ω/2) = a·(b×c) / (|a||b||c| + (a·b)|c| + (a·c)|b| + (b·c)|a|).
// The sign of det = a·(b×c) says which side the light at `eye` sees (+1 away, −1 facing it, 0
// edge-on or a face of the apex vertex `apex`); |det| within what moving each vertex by the face's
// own corner motion (and the view's `extra`) could change counts as edge-on. `*omega` is the
// signed solid angle.
// `near` (may be empty) holds the distances from the eye of some vertices, length(position −
// eye) as computed here, so the same to the bit.
int classify_from_point(const Mesh& mesh, std::size_t t, const LightView& view, double* omega,
                        const NearDistances& near = {}) {
  const Vec3d& eye = view.eye;
  const auto [ia, ib, ic] = mesh.triangle(t);
  if (ia == view.apex || ib == view.apex || ic == view.apex) {
    *omega = 0;
    return 0;
  }
  const Vec3d pa = position(mesh, ia), pb = position(mesh, ib), pc = position(mesh, ic);
  const double motion = corner_motion(pa, pb, pc) + view.extra;
  const Vec3d a = pa - eye, b = pb - eye, c = pc - eye;
  const Vec3d bc = cross(b, c);
  const double det = dot(a, bc);
  const double la = near.of(ia, a), lb = near.of(ib, b), lc = near.of(ic, c);
  const double denom = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
  *omega = 2 * small_atan2(det, denom);
  // |b × c| ≤ |b||c| (with room for their rounding): most faces are decided without the cross
  // products' lengths.
  if (det > motion * (lb * lc + lc * la + la * lb) * (1 + 1e-12)) return 1;
  return side_from_point(a, b, c, bc, det, motion);
}

// Directional: +1 (an exit: normal along f), −1 (a face on the wrong side), 0 (edge-on), or 2
// (an entry: a near-plane face facing the light); `area` is the signed projected area.
int classify_along(const Mesh& mesh, std::size_t t, const LightView& view, double* area) {
  const Vec3d& f = view.f;
  const auto [ia, ib, ic] = mesh.triangle(t);
  const Vec3d a = position(mesh, ia), b = position(mesh, ib), c = position(mesh, ic);
  const double motion = corner_motion(a, b, c) + view.extra;
  const auto on_near_plane = [&](const Vec3d& p) {
    return std::abs(dot(p - view.origin, f)) <= motion;
  };
  *area = 0.5 * dot(cross(b - a, c - a), f);
  const bool source = on_near_plane(a) && on_near_plane(b) && on_near_plane(c);
  return side_along(a, b, c, f, *area, source, motion);
}

// The light sums of faces [begin, end), split as parallel_deterministic_reduce splits a range
// with grain 2^14 and summed in its order, so that the sums do not depend on the threads.
constexpr std::size_t kLightGrain = std::size_t{1} << 14;

// From a point light, faces are taken kLanes at a time: a loop without branches, which the
// compiler vectorizes, computes each face's determinant (of the volume sum), whether its cross
// product is zero, and its solid angle when it is decided there: seen from behind by more than its
// tolerance (classify_from_point's quick test or side_from_point's) and small_atan2's series
// applies. Every other face (edge-on, facing the light, at the apex, a repeated vertex, a large
// angle, NaN) is classified again by classify_from_point. Each value is the same expression, term
// for term, as the scalar code's, so the same double (the file is compiled without contraction
// into fused multiply-adds, so the vector versions for wider instruction sets round as it does).
constexpr std::size_t kLanes = 256;

struct FaceLanes {
  double det[kLanes], omega[kLanes];
  double flat[kLanes], decided[kLanes];  // 0 or 1, doubles: one vector type in the loop
};

// Faces [0, n) of `tri` (three vertices each); `distance[v - first]` is vertex v's distance from
// the eye.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
[[gnu::target_clones("avx512f", "avx2", "default")]]
#endif
[[gnu::noinline]] void
decide_lanes(const std::uint32_t* tri, const float* p, const double* distance, std::uint32_t first,
             std::size_t n, Vec3d eye, double extra, FaceLanes& f) {
#pragma omp simd
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t ia = tri[3 * i], ib = tri[3 * i + 1], ic = tri[3 * i + 2];
    const double pax = p[3 * std::size_t{ia}], pay = p[3 * std::size_t{ia} + 1],
                 paz = p[3 * std::size_t{ia} + 2];
    const double pbx = p[3 * std::size_t{ib}], pby = p[3 * std::size_t{ib} + 1],
                 pbz = p[3 * std::size_t{ib} + 2];
    const double pcx = p[3 * std::size_t{ic}], pcy = p[3 * std::size_t{ic} + 1],
                 pcz = p[3 * std::size_t{ic} + 2];
    // volume_det
    f.det[i] = pax * (pby * pcz - pbz * pcy) - pay * (pbx * pcz - pbz * pcx) +
               paz * (pbx * pcy - pby * pcx);
    // is_degenerate's cross product
    const double ux = pbx - pax, uy = pby - pay, uz = pbz - paz;
    const double vx = pcx - pax, vy = pcy - pay, vz = pcz - paz;
    const double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
    f.flat[i] = ((nx == 0) & (ny == 0) & (nz == 0)) ? 1.0 : 0.0;
    // corner_motion + extra
    const double big_a = std::max(std::max(std::abs(pax), std::abs(pay)), std::abs(paz));
    const double big_b = std::max(std::max(std::abs(pbx), std::abs(pby)), std::abs(pbz));
    const double big_c = std::max(std::max(std::abs(pcx), std::abs(pcy)), std::abs(pcz));
    const double motion = 8 * (std::max(std::max(big_a, big_b), big_c) * 0x1p-23) + extra;
    // classify_from_point
    const double ax = pax - eye.x, ay = pay - eye.y, az = paz - eye.z;
    const double bx = pbx - eye.x, by = pby - eye.y, bz = pbz - eye.z;
    const double cx = pcx - eye.x, cy = pcy - eye.y, cz = pcz - eye.z;
    const double la = distance[ia - first], lb = distance[ib - first], lc = distance[ic - first];
    const double bcx = by * cz - bz * cy, bcy = bz * cx - bx * cz, bcz = bx * cy - by * cx;
    const double det = ax * bcx + ay * bcy + az * bcz;
    const double ab = ax * bx + ay * by + az * bz;
    const double ac = ax * cx + ay * cy + az * cz;
    const double bc = bx * cx + by * cy + bz * cz;
    const double denom = la * lb * lc + ab * lc + ac * lb + bc * la;
    // small_atan2's series (its other case is not decided here)
    const double r = det / denom, r2 = r * r;
    f.omega[i] = 2 * (r * (1 - r2 * (1.0 / 3 - r2 * (1.0 / 5))));
    // Seen from behind: the quick test, else side_from_point's, with the cross products' lengths.
    const double cax = cy * az - cz * ay, cay = cz * ax - cx * az, caz = cx * ay - cy * ax;
    const double abx = ay * bz - az * by, aby = az * bx - ax * bz, abz = ax * by - ay * bx;
    const double tol = motion * (std::sqrt(bcx * bcx + bcy * bcy + bcz * bcz) +
                                 std::sqrt(cax * cax + cay * cay + caz * caz) +
                                 std::sqrt(abx * abx + aby * aby + abz * abz));
    const bool series = (denom > 0) & (std::abs(det) <= 1e-3 * denom);
    const bool quick = det > motion * (lb * lc + lc * la + la * lb) * (1 + 1e-12);
    f.decided[i] = (series & (quick | (det > tol))) ? 1.0 : 0.0;
  }
}

// In the same loop, the faces' determinants are added to `*det` in face order (as signed_volume
// adds them) and the degenerate faces counted: the faces are read once.
LightSums light_sums(const Mesh& mesh, const LightView& view, std::size_t begin, std::size_t end,
                     std::vector<std::pair<std::uint32_t, std::uint32_t>>* apex_link, double* det,
                     std::uint64_t* degenerate) {
  if (end - begin > kLightGrain) {
    const std::size_t middle = begin + (end - begin) / 2;
    const LightSums left = light_sums(mesh, view, begin, middle, apex_link, det, degenerate);
    return left + light_sums(mesh, view, middle, end, apex_link, det, degenerate);
  }
  LightSums s;
  const float* p = mesh.positions.data();
  const std::uint32_t* idx = mesh.indices.data();
  // From a point: the distances of the vertices the faces name, when they span a range of at most
  // twice as many vertices as there are faces (faces in vertex order, as build writes them).
  NearDistances near;
  thread_local std::vector<double> distances;
  if (view.kind == LightView::Kind::point && end > begin) {
    const auto [lo, hi] = std::minmax_element(idx + 3 * begin, idx + 3 * end);
    if (*hi - *lo < 2 * (end - begin)) {
      near.first = *lo;
      near.size = *hi - *lo + 1;
      distances.resize(near.size);
      for (std::uint32_t k = 0; k < near.size; ++k)
        distances[k] = length(position(mesh, near.first + k) - view.eye);
      near.distance = distances.data();
    }
  }
  double acc = *det;
  std::uint64_t zero_area = 0;
  // A face classify_from_point decides: its solid angle summed by its side.
  const auto add_point_face = [&](std::size_t t) {
    double omega = 0;
    const int side = classify_from_point(mesh, t, view, &omega, near);
    if (side > 0) {
      s.positive += omega;
    } else if (side < 0) {
      s.negative -= omega;
      ++s.wrong;
    } else {
      s.zeroed += std::abs(omega);
      const auto tri = mesh.triangle(t);
      for (int k = 0; k < 3; ++k)
        if (tri[k] == view.apex) apex_link->emplace_back(tri[(k + 1) % 3], tri[(k + 2) % 3]);
    }
  };
  if (near.distance && view.lanes && vector_lanes()) {
    // Every vertex the faces name has its distance: the faces kLanes at a time.
    const auto lanes = std::make_unique_for_overwrite<FaceLanes>();
    FaceLanes& f = *lanes;
    // The decided faces in a loop without calls, so that its sums stay in registers; it stops at
    // each face add_point_face must classify (which adds to s.positive itself, in face order).
    double positive = s.positive;
    for (std::size_t first = begin; first < end; first += kLanes) {
      const std::size_t n = std::min(kLanes, end - first);
      decide_lanes(idx + 3 * first, p, near.distance, near.first, n, view.eye, view.extra, f);
      for (std::size_t i = 0; i < n; ++i) {
        for (; i < n; ++i) {
          const auto [ia, ib, ic] = mesh.triangle(first + i);
          const bool repeated = ia == ib || ib == ic || ia == ic;
          const bool apex = ia == view.apex || ib == view.apex || ic == view.apex;
          acc += f.det[i];
          zero_area += repeated || f.flat[i] != 0 ? 1 : 0;
          if (f.decided[i] == 0 || repeated || apex) break;
          positive += f.omega[i];
        }
        if (i == n) break;
        // Face first + i: its determinant and area are counted, its side is not.
        s.positive = positive;
        add_point_face(first + i);
        positive = s.positive;
      }
    }
    s.positive = positive;
    *det = acc;
    *degenerate += zero_area;
    return s;
  }
  for (std::size_t t = begin; t != end; ++t) {
    acc += volume_det(p + 3 * idx[3 * t], p + 3 * idx[3 * t + 1], p + 3 * idx[3 * t + 2]);
    zero_area += is_degenerate(mesh, t);
    if (view.kind == LightView::Kind::point) {
      add_point_face(t);
      continue;
    }
    double area = 0;
    switch (classify_along(mesh, t, view, &area)) {
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
  *det = acc;
  *degenerate += zero_area;
  return s;
}

// The body of the face pass's parallel_deterministic_reduce, over leaves of at most
// kSignedVolumeGrain faces: each leaf sums its determinants in order as signed_volume does, and its
// light sums as the tree of kLightGrain leaves below it.
class FacePass {
 public:
  FacePass(const Mesh& mesh, const LightView& view) : mesh_(mesh), view_(view) {}
  FacePass(FacePass& other, tbb::split) : mesh_(other.mesh_), view_(other.view_) {}
  void operator()(const tbb::blocked_range<std::size_t>& range) {
    if (view_.kind != LightView::Kind::none) {
      sums.light = sums.light + light_sums(mesh_, view_, range.begin(), range.end(),
                                           &sums.apex_link, &sums.det, &sums.degenerate);
      return;
    }
    const float* p = mesh_.positions.data();
    const std::uint32_t* idx = mesh_.indices.data();
    double acc = sums.det;
    std::uint64_t degenerate = 0;
    for (std::size_t t = range.begin(); t != range.end(); ++t) {
      acc += volume_det(p + 3 * idx[3 * t], p + 3 * idx[3 * t + 1], p + 3 * idx[3 * t + 2]);
      degenerate += is_degenerate(mesh_, t);
    }
    sums.det = acc;
    sums.degenerate += degenerate;
  }
  void join(FacePass& right) {
    sums.det += right.sums.det;
    sums.degenerate += right.sums.degenerate;
    sums.light = sums.light + right.sums.light;
    sums.apex_link.insert(sums.apex_link.end(), right.sums.apex_link.begin(),
                          right.sums.apex_link.end());
  }
  FaceSums sums;

 private:
  const Mesh& mesh_;
  const LightView& view_;
};

}  // namespace

LightView point_view(const Mesh& mesh, const Light& light, const VertexScan& scan, double quantum) {
  // The light at a vertex (a spot volume's apex): view from that vertex's exact position, so the
  // faces around it are exactly degenerate and the cone is measured from the same point.
  LightView view;
  view.kind = LightView::Kind::point;
  const bool at_vertex = scan.at_light.size() == 1;
  view.eye = at_vertex ? position(mesh, scan.at_light.front()) : light.position;
  view.apex = at_vertex ? scan.at_light.front() : ~0u;
  view.extra = quantum + frame_motion(view.eye);
  return view;
}

LightView directional_view(const Light& light, double quantum) {
  LightView view;
  view.kind = LightView::Kind::directional;
  view.f = normalize(light.direction);
  view.origin = light.position + light.near * view.f;
  view.extra = quantum + std::max(frame_motion(view.origin), frame_motion(light.position));
  return view;
}

FaceSums face_pass(const Mesh& mesh, const LightView& view) {
  FacePass body(mesh, view);
  tbb::parallel_deterministic_reduce(
      tbb::blocked_range<std::size_t>(0, mesh.num_triangles(), kSignedVolumeGrain), body);
  return std::move(body.sums);
}

CheckResult nesting_check_point(const Mesh& mesh, const VertexScan& scan, const LightView& view,
                                const FaceSums& face_sums, double quantum, int max_offenders,
                                CheckReport* report) {
  CheckResult r;
  r.name = kCheckNesting;
  report->proof = NestingProof::solid_angles;
  const std::vector<std::uint32_t>& at_light = scan.at_light;
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
  const std::uint32_t apex = view.apex;

  const std::size_t nt = mesh.num_triangles();
  const LightSums& sums = face_sums.light;
  if (sums.wrong > 0) {
    for (std::size_t t = 0; t < nt && r.offenders.size() < static_cast<std::size_t>(max_offenders);
         ++t) {
      double omega = 0;
      if (classify_from_point(mesh, t, view, &omega) < 0)
        r.offenders.push_back(face_offender(mesh, t));
    }
  }

  double expected = 4 * kPi;
  std::string where = "the light inside";
  if (at_vertex) {
    expected = apex_cone_solid_angle(mesh, face_sums.apex_link, view.eye);
    where = "the light at vertex " + std::to_string(apex);
    if (scan.light_offset > 4 * scan.light_ulp) {
      std::ostringstream off;
      off.precision(3);
      off << " (" << scan.light_offset << " from it, within the positions' quantization step "
          << quantum << ")";
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

CheckResult nesting_check_directional(const Mesh& mesh, const LightView& view,
                                      const FaceSums& face_sums, int max_offenders,
                                      CheckReport* report) {
  CheckResult r;
  r.name = kCheckNesting;
  report->proof = NestingProof::projected_areas;
  const std::size_t nt = mesh.num_triangles();
  const LightSums& sums = face_sums.light;
  if (sums.wrong > 0) {
    for (std::size_t t = 0; t < nt && r.offenders.size() < static_cast<std::size_t>(max_offenders);
         ++t) {
      double area = 0;
      if (classify_along(mesh, t, view, &area) == -1) r.offenders.push_back(face_offender(mesh, t));
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

}  // namespace lightvol
