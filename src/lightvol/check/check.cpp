// The linear-time checks (closed, edge-manifold, oriented, outward, non-degenerate, T-junctions)
// and the light's non-self-nesting proof. CGAL's checks are in cgal_checks.cpp.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <unordered_map>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <lightvol/check/check.h>
#include <lightvol/check/detail/cgal_checks.h>
#include <lightvol/core/check.h>
#include <lightvol/core/math.h>

namespace lightvol {

std::string_view to_string(CheckStatus status) {
  switch (status) {
    case CheckStatus::passed:
      return "pass";
    case CheckStatus::failed:
      return "FAIL";
    case CheckStatus::skipped:
      return "skipped";
  }
  return "?";
}

std::string_view to_string(NestingProof proof) {
  switch (proof) {
    case NestingProof::none:
      return "none";
    case NestingProof::solid_angles:
      return "light: signed solid angles";
    case NestingProof::projected_areas:
      return "light: signed projected areas";
    case NestingProof::cgal:
      return "CGAL: self-intersections + bounds a volume";
  }
  return "?";
}

bool CheckReport::valid() const {
  for (const CheckResult& c : checks)
    if (c.status == CheckStatus::failed) return false;
  const CheckResult* nesting = find(kCheckNesting);
  return nesting && nesting->status == CheckStatus::passed;
}

const CheckResult* CheckReport::find(std::string_view name) const {
  for (const CheckResult& c : checks)
    if (c.name == name) return &c;
  return nullptr;
}

std::string CheckReport::first_failure() const {
  for (const CheckResult& c : checks) {
    if (c.status != CheckStatus::failed) continue;
    std::ostringstream out;
    out << c.name << ": " << c.detail;
    if (!c.offenders.empty()) {
      const Offender& o = c.offenders.front();
      out << "; first:";
      if (!o.faces.empty()) {
        out << (o.faces.size() == 1 ? " face" : " faces");
        for (std::int64_t f : o.faces) out << ' ' << f;
      }
      out << " at vertices";
      for (std::size_t k = 0; k < o.vertices.size(); ++k) {
        const auto& p = o.positions[k];
        out << ' ' << o.vertices[k] << " (" << p[0] << ", " << p[1] << ", " << p[2] << ")";
      }
    }
    return out.str();
  }
  if (!valid()) return std::string(kCheckNesting) + ": not proved (no light, and CGAL did not run)";
  return {};
}

namespace {

constexpr double kPi = std::numbers::pi;

Vec3d position(const Mesh& mesh, std::uint32_t v) {
  return {mesh.positions[3 * v], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2]};
}

Offender make_offender(const Mesh& mesh, std::vector<std::int64_t> faces,
                       std::vector<std::uint32_t> vertices) {
  Offender o;
  o.faces = std::move(faces);
  o.vertices = std::move(vertices);
  for (std::uint32_t v : o.vertices) o.positions.push_back(mesh.vertex(v));
  return o;
}

Offender face_offender(const Mesh& mesh, std::size_t t) {
  const auto [a, b, c] = mesh.triangle(t);
  return make_offender(mesh, {static_cast<std::int64_t>(t)}, {a, b, c});
}

CheckResult skipped(std::string_view name, std::string why) {
  CheckResult r;
  r.name = name;
  r.status = CheckStatus::skipped;
  r.detail = std::move(why);
  return r;
}

bool passed(const CheckReport& report, std::string_view name) {
  const CheckResult* c = report.find(name);
  return c && c->status == CheckStatus::passed;
}

// One use of an undirected edge {lo, hi} by face `face`, running lo→hi (forward) or hi→lo.
struct EdgeUse {
  std::uint64_t edge;      // lo << 32 | hi
  std::uint32_t face_dir;  // face << 1 | (runs hi→lo)
  bool operator<(const EdgeUse& o) const {
    return edge != o.edge ? edge < o.edge : face_dir < o.face_dir;
  }
};

struct EdgeResults {
  CheckResult closed, manifold, oriented;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> boundary;  // directed, as in their face
  std::vector<std::int64_t> boundary_faces;
};

// Buckets every edge use by its lower vertex (a counting sort, linear), sorts each small bucket,
// and reads closedness, manifoldness and orientation off the groups of equal edges.
EdgeResults edge_checks(const Mesh& mesh, int max_offenders) {
  const std::size_t nt = mesh.num_triangles(), nv = mesh.num_vertices();
  const auto use_of = [&](std::size_t t, int k) {
    const std::uint64_t a = mesh.indices[3 * t + k];
    const std::uint64_t b = mesh.indices[3 * t + (k + 1) % 3];
    return EdgeUse{std::min(a, b) << 32 | std::max(a, b),
                   static_cast<std::uint32_t>(t << 1 | (a > b ? 1 : 0))};
  };
  std::vector<std::uint32_t> start(nv + 1, 0);
  for (std::size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k)
      ++start[std::min(mesh.indices[3 * t + k], mesh.indices[3 * t + (k + 1) % 3]) + 1];
  for (std::size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
  std::vector<EdgeUse> uses(3 * nt);
  {
    std::vector<std::uint32_t> next(start.begin(), start.end() - 1);
    for (std::size_t t = 0; t < nt; ++t)
      for (int k = 0; k < 3; ++k) {
        const EdgeUse u = use_of(t, k);
        uses[next[u.edge >> 32]++] = u;
      }
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 1 << 12),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t v = r.begin(); v != r.end(); ++v)
                        std::sort(uses.begin() + start[v], uses.begin() + start[v + 1]);
                    });

  EdgeResults out;
  out.closed.name = kCheckClosed;
  out.manifold.name = kCheckManifold;
  out.oriented.name = kCheckOriented;
  const auto lo_of = [](std::uint64_t e) { return static_cast<std::uint32_t>(e >> 32); };
  const auto hi_of = [](std::uint64_t e) { return static_cast<std::uint32_t>(e & 0xffffffffu); };
  // The first 16 faces of an edge: an edge shared by 600,000 faces (all at one point) must not
  // make a megabyte-long message.
  const auto faces_of = [&](std::size_t i, std::size_t j) {
    std::vector<std::int64_t> faces;
    for (std::size_t k = i; k < j && k < i + 16; ++k) faces.push_back(uses[k].face_dir >> 1);
    return faces;
  };
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i + 1;
    while (j < uses.size() && uses[j].edge == uses[i].edge) ++j;
    const std::uint64_t e = uses[i].edge;
    const std::size_t n = j - i;
    if (n == 1) {
      const bool reversed = uses[i].face_dir & 1;
      const std::uint32_t from = reversed ? hi_of(e) : lo_of(e),
                          to = reversed ? lo_of(e) : hi_of(e);
      out.boundary.emplace_back(from, to);
      out.boundary_faces.push_back(uses[i].face_dir >> 1);
      if (out.closed.count++ < static_cast<std::uint64_t>(max_offenders))
        out.closed.offenders.push_back(make_offender(mesh, faces_of(i, j), {from, to}));
    } else if (n > 2) {
      if (out.manifold.count++ < static_cast<std::uint64_t>(max_offenders))
        out.manifold.offenders.push_back(make_offender(mesh, faces_of(i, j), {lo_of(e), hi_of(e)}));
    } else if ((uses[i].face_dir & 1) == (uses[i + 1].face_dir & 1)) {
      if (out.oriented.count++ < static_cast<std::uint64_t>(max_offenders))
        out.oriented.offenders.push_back(make_offender(mesh, faces_of(i, j), {lo_of(e), hi_of(e)}));
    }
    i = j;
  }
  const auto finish = [](CheckResult& c, const std::string& what) {
    c.status = c.count == 0 ? CheckStatus::passed : CheckStatus::failed;
    c.detail = std::to_string(c.count) + " " + what;
  };
  finish(out.closed, "boundary edges (used by one face)");
  finish(out.manifold, "edges used by more than two faces");
  finish(out.oriented, "edges running the same way in both their faces");
  return out;
}

// Faces with a repeated vertex or a cross product of exactly zero (double precision, exact for
// float inputs up to the last rounding).
CheckResult degenerate_check(const Mesh& mesh, int max_offenders) {
  CheckResult r;
  r.name = kCheckDegenerate;
  const std::size_t nt = mesh.num_triangles();
  const auto is_degenerate = [&](std::size_t t) {
    const auto [a, b, c] = mesh.triangle(t);
    if (a == b || b == c || a == c) return true;
    const Vec3d pa = position(mesh, a);
    const Vec3d n = cross(position(mesh, b) - pa, position(mesh, c) - pa);
    return n.x == 0 && n.y == 0 && n.z == 0;
  };
  r.count = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, nt, 1 << 15), std::uint64_t{0},
      [&](const tbb::blocked_range<std::size_t>& range, std::uint64_t n) {
        for (std::size_t t = range.begin(); t != range.end(); ++t) n += is_degenerate(t);
        return n;
      },
      [](std::uint64_t x, std::uint64_t y) { return x + y; });
  for (std::size_t t = 0;
       t < nt && r.offenders.size() < static_cast<std::size_t>(max_offenders) && r.count > 0; ++t)
    if (is_degenerate(t)) r.offenders.push_back(face_offender(mesh, t));
  r.status = r.count == 0 ? CheckStatus::passed : CheckStatus::failed;
  r.detail = std::to_string(r.count) + " faces with zero area or a repeated vertex";
  return r;
}

// T-junctions: a boundary vertex lying inside a boundary edge (strictly between its ends, within
// a millionth of the edge's length plus float rounding). Boundary vertices are binned in a grid
// whose cells are the mean boundary edge length; each edge visits the cells along it.
CheckResult t_junction_check(const Mesh& mesh, const EdgeResults& edges, double eps_pos,
                             int max_offenders) {
  CheckResult r;
  r.name = kCheckTJunctions;
  if (edges.boundary.empty()) {
    r.status = CheckStatus::passed;
    r.detail = "no boundary edges";
    return r;
  }
  std::vector<std::uint32_t> verts;
  double total_length = 0;
  for (const auto& [u, v] : edges.boundary) {
    verts.push_back(u);
    verts.push_back(v);
    total_length += length(position(mesh, v) - position(mesh, u));
  }
  std::sort(verts.begin(), verts.end());
  verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
  const double cell = std::max(total_length / static_cast<double>(edges.boundary.size()), 1e-30);
  // Grid cell of a point; coordinates far beyond the grid's reach are clamped (a cell index must
  // fit an int64), and the hash works in unsigned arithmetic, where overflow wraps.
  const auto axis_cell = [&](double x) {
    const double c = std::floor(x / cell);
    return std::isfinite(c) ? static_cast<std::int64_t>(std::clamp(c, -4.0e15, 4.0e15)) : 0;
  };
  const auto cell_of = [&](Vec3d p) {
    return std::array<std::int64_t, 3>{axis_cell(p.x), axis_cell(p.y), axis_cell(p.z)};
  };
  const auto key_of = [](std::array<std::int64_t, 3> c) {
    return static_cast<std::uint64_t>(c[0]) * 73856093u ^
           static_cast<std::uint64_t>(c[1]) * 19349663u ^
           static_cast<std::uint64_t>(c[2]) * 83492791u;
  };
  std::unordered_multimap<std::uint64_t, std::uint32_t> grid;
  grid.reserve(verts.size());
  for (std::uint32_t v : verts) grid.emplace(key_of(cell_of(position(mesh, v))), v);

  std::unordered_map<std::uint32_t, bool> reported;
  for (std::size_t e = 0; e < edges.boundary.size(); ++e) {
    const auto [u, v] = edges.boundary[e];
    const Vec3d pu = position(mesh, u), pv = position(mesh, v), d = pv - pu;
    const double len2 = dot(d, d);
    if (len2 == 0) continue;
    const double len = std::sqrt(len2);
    const double tol = 1e-6 * len + 4 * eps_pos;
    const int steps = static_cast<int>(std::min(len / cell, 1e7)) + 1;
    std::vector<std::uint64_t> visited;
    for (int s = 0; s <= steps; ++s) {
      const auto c = cell_of(pu + (static_cast<double>(s) / steps) * d);
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            const std::uint64_t key = key_of({c[0] + dx, c[1] + dy, c[2] + dz});
            if (std::find(visited.begin(), visited.end(), key) != visited.end()) continue;
            visited.push_back(key);
            const auto [first, last] = grid.equal_range(key);
            for (auto it = first; it != last; ++it) {
              const std::uint32_t w = it->second;
              if (w == u || w == v || reported.count(w)) continue;
              const Vec3d pw = position(mesh, w);
              const double t = dot(pw - pu, d) / len2;
              if (t * len <= tol || (1 - t) * len <= tol) continue;
              if (length(pw - (pu + t * d)) > tol) continue;
              reported[w] = true;
              if (r.count++ < static_cast<std::uint64_t>(max_offenders))
                r.offenders.push_back(make_offender(mesh, {edges.boundary_faces[e]}, {w, u, v}));
            }
          }
    }
  }
  r.status = r.count == 0 ? CheckStatus::passed : CheckStatus::failed;
  r.detail = std::to_string(r.count) + " vertices lying inside another face's edge";
  return r;
}

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

CheckResult nesting_check_point(const Mesh& mesh, const Light& light, double eps_pos,
                                double quantum, int max_offenders, CheckReport* report) {
  CheckResult r;
  r.name = kCheckNesting;
  report->proof = NestingProof::solid_angles;
  // The light at a vertex (a spot volume's apex): view from that vertex's exact position, so the
  // faces around it are exactly degenerate and the cone is measured from the same point.
  const Vec3d light_pos = light.position;
  std::vector<std::uint32_t> at_light;
  // "At the light" means within the rounding of coordinates there (a few float ulps of the light's
  // own position), not of the largest coordinate: a spot volume's near plane can lie 10^-6 of the
  // far distance from its apex. Quantized positions are only known to within their step.
  const double light_ulp =
      std::ldexp(std::max({std::abs(light_pos.x), std::abs(light_pos.y), std::abs(light_pos.z),
                           static_cast<double>(std::numeric_limits<float>::min())}),
                 -23);
  const double at_light_tol = std::max(4 * light_ulp, quantum);
  double light_offset = 0;  // of the vertex at the light, max-norm
  for (std::size_t v = 0; v < mesh.num_vertices(); ++v) {
    const Vec3d d = position(mesh, static_cast<std::uint32_t>(v)) - light_pos;
    const double offset = std::max({std::abs(d.x), std::abs(d.y), std::abs(d.z)});
    if (offset <= at_light_tol) {
      at_light.push_back(static_cast<std::uint32_t>(v));
      light_offset = offset;
    }
  }
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

  // Van Oosterom–Strackee: tan(Ω/2) = a·(b×c) / (|a||b||c| + (a·b)|c| + (a·c)|b| + (b·c)|a|).
  // The sign of det = a·(b×c) says which side the light sees; |det| within what moving each
  // vertex by the rounding tolerance could change counts as edge-on.
  const auto classify = [&](std::size_t t, double* omega) -> int {
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
  };
  const std::size_t nt = mesh.num_triangles();
  const LightSums sums = tbb::parallel_deterministic_reduce(
      tbb::blocked_range<std::size_t>(0, nt, 1 << 14), LightSums{},
      [&](const tbb::blocked_range<std::size_t>& range, LightSums s) {
        for (std::size_t t = range.begin(); t != range.end(); ++t) {
          double omega = 0;
          const int side = classify(t, &omega);
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
  if (sums.wrong > 0) {
    for (std::size_t t = 0; t < nt && r.offenders.size() < static_cast<std::size_t>(max_offenders);
         ++t) {
      double omega = 0;
      if (classify(t, &omega) < 0) r.offenders.push_back(face_offender(mesh, t));
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

}  // namespace

Light light_in_space(const Light& light, Space space) {
  if (space == Space::world) return light;
  Light out = light;
  out.position = {0, 0, 0};
  // Omni light space keeps world axes; spot and directional look down their eye space's −Z.
  if (light.type != LightType::omni) out.direction = {0, 0, -1};
  return out;
}

CheckReport check_volume_linear(const Mesh& mesh, const Light* light, int max_offenders,
                                double quantization_step) {
  CheckReport report;
  report.vertices = mesh.num_vertices();
  report.triangles = mesh.num_triangles();
  report.bounds = bounding_box(mesh);
  report.quantization_step = quantization_step;

  // Indices first: nothing else can look at a face that names a missing vertex.
  CheckResult indices;
  indices.name = kCheckIndices;
  const std::size_t nv = mesh.num_vertices();
  const bool too_big = mesh.num_triangles() >= (std::size_t{1} << 31);
  for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
    const auto [a, b, c] = mesh.triangle(t);
    if (a >= nv || b >= nv || c >= nv) {
      if (indices.count++ < static_cast<std::uint64_t>(max_offenders)) {
        Offender o;
        o.faces = {static_cast<std::int64_t>(t)};
        indices.offenders.push_back(o);
      }
    }
  }
  indices.status = indices.count == 0 && !too_big && mesh.num_triangles() > 0 ? CheckStatus::passed
                                                                              : CheckStatus::failed;
  indices.detail = mesh.num_triangles() == 0 ? "the mesh has no triangles"
                   : too_big                 ? "more than 2^31 triangles"
                             : std::to_string(indices.count) + " faces name a vertex beyond the " +
                                   std::to_string(nv) + " vertices";
  report.checks.push_back(indices);
  if (indices.status != CheckStatus::passed) {
    for (std::string_view name : {kCheckClosed, kCheckManifold, kCheckOriented, kCheckOutward,
                                  kCheckDegenerate, kCheckTJunctions, kCheckNesting})
      report.checks.push_back(skipped(name, "the faces' indices are invalid"));
    return report;
  }

  double max_abs = 0;
  for (float x : mesh.positions) max_abs = std::max(max_abs, static_cast<double>(std::abs(x)));
  if (light) {
    for (int k = 0; k < 3; ++k) max_abs = std::max(max_abs, std::abs(light->position[k]));
  }
  // The rounding of a coordinate to float: half an ulp of the largest, doubled for safety.
  const double eps_pos = std::ldexp(max_abs, -23);

  EdgeResults edges = edge_checks(mesh, max_offenders);
  report.checks.push_back(edges.closed);
  report.checks.push_back(edges.manifold);
  report.checks.push_back(edges.oriented);
  report.volume = signed_volume(mesh);
  const bool topology = passed(report, kCheckClosed) && passed(report, kCheckManifold) &&
                        passed(report, kCheckOriented);
  if (topology) {
    CheckResult outward;
    outward.name = kCheckOutward;
    outward.status = report.volume > 0 ? CheckStatus::passed : CheckStatus::failed;
    outward.count = report.volume > 0 ? 0 : 1;
    std::ostringstream detail;
    detail.precision(9);
    detail << "signed volume " << report.volume
           << (report.volume > 0 ? "" : ": the faces point inward");
    outward.detail = detail.str();
    report.checks.push_back(outward);
  } else {
    report.checks.push_back(skipped(kCheckOutward, "needs a closed, edge-manifold, oriented mesh"));
  }
  report.checks.push_back(degenerate_check(mesh, max_offenders));
  report.checks.push_back(t_junction_check(mesh, edges, eps_pos, max_offenders));

  if (!light) {
    report.checks.push_back(skipped(kCheckNesting, "no light given (CGAL's proof runs in check)"));
  } else if (!topology) {
    report.checks.push_back(skipped(kCheckNesting, "needs a closed, edge-manifold, oriented mesh"));
  } else if (light->type == LightType::directional) {
    report.checks.push_back(nesting_check_directional(mesh, *light, eps_pos, quantization_step,
                                                      max_offenders, &report));
  } else {
    report.checks.push_back(
        nesting_check_point(mesh, *light, eps_pos, quantization_step, max_offenders, &report));
  }
  return report;
}

CheckReport check_volume(const Mesh& mesh, const Light* light, const CheckOptions& options) {
  CheckReport report =
      check_volume_linear(mesh, light, options.max_offenders, options.quantization_step);
  const auto nesting_it =
      std::find_if(report.checks.begin(), report.checks.end(),
                   [](const CheckResult& c) { return c.name == kCheckNesting; });
  LV_CHECK(nesting_it != report.checks.end());
  const std::size_t nesting_at = static_cast<std::size_t>(nesting_it - report.checks.begin());
  const bool light_proved = nesting_it->status == CheckStatus::passed;

  std::vector<CheckResult> cgal;
  if (light && !options.cgal_with_light) {
    const std::string why = light_proved
                                ? "implied by the light's non-self-nesting proof"
                                : "not run with a light (CheckOptions::cgal_with_light runs it)";
    CheckResult si = skipped(kCheckSelfIntersections, why), bv = skipped(kCheckBoundsVolume, why);
    if (light_proved) si.status = bv.status = CheckStatus::passed;
    cgal = {si, bv};
  } else if (!passed(report, kCheckIndices) || !passed(report, kCheckManifold) ||
             !passed(report, kCheckOriented)) {
    cgal = {skipped(kCheckSelfIntersections, "needs an edge-manifold, oriented mesh"),
            skipped(kCheckBoundsVolume, "needs a closed, edge-manifold, oriented mesh")};
    if (!light) report.checks[nesting_at].detail = "needs a closed, edge-manifold, oriented mesh";
  } else {
    const detail::CgalChecks c =
        detail::cgal_checks(mesh, passed(report, kCheckClosed),
                            static_cast<std::size_t>(std::max(options.max_offenders, 1)));
    CheckResult si;
    si.name = kCheckSelfIntersections;
    if (!c.built) {
      si = skipped(kCheckSelfIntersections, c.why_not);
    } else {
      si.count = c.intersecting_pairs;
      si.status = c.intersecting_pairs == 0 ? CheckStatus::passed : CheckStatus::failed;
      si.detail = std::to_string(c.intersecting_pairs) + (c.pairs_truncated ? " or more" : "") +
                  " pairs of intersecting faces";
      for (const auto& [f, g] : c.first_pairs) {
        const auto [a, b, cc] = mesh.triangle(f);
        const auto [d, e, h] = mesh.triangle(g);
        si.offenders.push_back(
            make_offender(mesh, {static_cast<std::int64_t>(f), static_cast<std::int64_t>(g)},
                          {a, b, cc, d, e, h}));
      }
    }
    CheckResult bv;
    if (!c.ran_volume_test) {
      bv = skipped(kCheckBoundsVolume,
                   c.built ? "needs a closed mesh without self-intersections" : c.why_not);
    } else {
      bv.name = kCheckBoundsVolume;
      bv.status = c.bounds_a_volume ? CheckStatus::passed : CheckStatus::failed;
      bv.count = c.bounds_a_volume ? 0 : 1;
      bv.detail = std::to_string(c.components) + " connected components" +
                  (c.bounds_a_volume ? ", nested with alternating orientation"
                                     : ": nested or oriented so that some region winds twice or "
                                       "negatively");
    }
    cgal = {si, bv};
    if (!light) {
      CheckResult nesting;
      nesting.name = kCheckNesting;
      report.proof = NestingProof::cgal;
      if (si.status == CheckStatus::passed && bv.status == CheckStatus::passed) {
        nesting.status = CheckStatus::passed;
        nesting.detail = "no self-intersections and CGAL finds it bounds a volume";
      } else if (si.status != CheckStatus::failed &&
                 (si.status == CheckStatus::skipped || bv.status == CheckStatus::skipped)) {
        nesting = skipped(kCheckNesting, "CGAL's tests could not run");
      } else {
        nesting.status = CheckStatus::failed;
        nesting.count = 1;
        nesting.detail = si.status == CheckStatus::failed ? "the surface intersects itself"
                                                          : "the mesh does not bound a volume";
      }
      report.checks[nesting_at] = nesting;
    }
  }
  report.checks.insert(report.checks.begin() + static_cast<std::ptrdiff_t>(nesting_at),
                       cgal.begin(), cgal.end());
  return report;
}

}  // namespace lightvol
