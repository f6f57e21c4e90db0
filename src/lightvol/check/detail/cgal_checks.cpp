// The only translation unit that includes CGAL (slow to compile): the flat Mesh becomes a
// CGAL::Surface_mesh here and nowhere else.
#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <mutex>

#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/Euler_operations.h>
#include <CGAL/box_intersection_d.h>
#include <tbb/parallel_for.h>

#include <lightvol/check/detail/cgal_checks.h>

namespace lightvol::detail {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
using FaceIndex = SurfaceMesh::Face_index;
namespace PMP = CGAL::Polygon_mesh_processing;
using Primitive = CGAL::AABB_face_graph_triangle_primitive<SurfaceMesh>;
using TreeTraits = CGAL::AABB_traits<Kernel, Primitive>;
using Tree = CGAL::AABB_tree<TreeTraits>;

constexpr std::size_t kMaxPairs = 10000;

// Faces keep their order, so face i of the Surface_mesh is triangle i of `mesh`, which the caller
// has found edge-manifold and oriented. Euler::add_faces links all faces at once: adding them one
// by one searches each vertex's ring for a gap, quadratic around a vertex of high degree. It does
// not link separate fans meeting at a vertex, so each vertex's ring is walked afterwards: it must
// hold every face at that vertex.
bool to_surface_mesh(const Mesh& mesh, SurfaceMesh* out, std::string* why_not) {
  const std::size_t nv = mesh.num_vertices(), nt = mesh.num_triangles();
  out->reserve(static_cast<SurfaceMesh::size_type>(nv),
               static_cast<SurfaceMesh::size_type>(3 * nt / 2),
               static_cast<SurfaceMesh::size_type>(nt));
  std::vector<SurfaceMesh::Vertex_index> vs(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    const auto p = mesh.vertex(v);
    vs[v] = out->add_vertex(Kernel::Point_3(p[0], p[1], p[2]));
  }
  std::vector<std::uint32_t> degree(nv, 0);
  std::vector<std::array<SurfaceMesh::Vertex_index, 3>> faces(nt);
  for (std::size_t t = 0; t < nt; ++t) {
    const auto [a, b, c] = mesh.triangle(t);
    if (a == b || b == c || a == c) {
      *why_not = "face " + std::to_string(t) + " repeats a vertex";
      return false;
    }
    faces[t] = {vs[a], vs[b], vs[c]};
    ++degree[a], ++degree[b], ++degree[c];
  }
  CGAL::Euler::add_faces(faces, *out);
  faces = {};
  for (std::size_t v = 0; v < nv; ++v) {
    if (degree[v] == 0) continue;
    std::uint32_t ring = 0;
    for (const FaceIndex f : CGAL::faces_around_target(out->halfedge(vs[v]), *out))
      ring += f != SurfaceMesh::null_face();
    if (ring == degree[v]) continue;
    for (std::size_t t = 0; t < nt; ++t) {
      const auto [a, b, c] = mesh.triangle(t);
      if (a == v || b == v || c == v) {
        *why_not = "face " + std::to_string(t) + " is at vertex " + std::to_string(v) +
                   ", where separate fans of faces meet (not a manifold surface)";
        break;
      }
    }
    return false;
  }
  return true;
}

// Does triangle (a, b, c) meet the box? The separating-axis test (Akenine-Möller) in double
// precision on a slightly inflated box: conservative (never says no to a pair that touches), so
// it only prunes the traversal; the exact test comes after.
bool triangle_may_meet_box(const std::array<std::array<double, 3>, 3>& tri,
                           const CGAL::Bbox_3& box) {
  std::array<double, 3> centre, half;
  for (int k = 0; k < 3; ++k) {
    centre[k] = 0.5 * (box.min(k) + box.max(k));
    half[k] = 0.5 * (box.max(k) - box.min(k));
    half[k] += 1e-9 * (std::abs(centre[k]) + half[k]) + 1e-300;
  }
  std::array<std::array<double, 3>, 3> v;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) v[i][k] = tri[i][k] - centre[k];
  const auto sub = [](const std::array<double, 3>& x, const std::array<double, 3>& y) {
    return std::array<double, 3>{x[0] - y[0], x[1] - y[1], x[2] - y[2]};
  };
  const auto cross3 = [](const std::array<double, 3>& x, const std::array<double, 3>& y) {
    return std::array<double, 3>{x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2],
                                 x[0] * y[1] - x[1] * y[0]};
  };
  const auto dot3 = [](const std::array<double, 3>& x, const std::array<double, 3>& y) {
    return x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
  };
  // Separated along `axis` when the triangle's projection misses the box's, with slack.
  const auto separated = [&](const std::array<double, 3>& axis) {
    const double p0 = dot3(v[0], axis), p1 = dot3(v[1], axis), p2 = dot3(v[2], axis);
    const double r =
        half[0] * std::abs(axis[0]) + half[1] * std::abs(axis[1]) + half[2] * std::abs(axis[2]);
    const double slack = 1e-9 * (std::abs(p0) + std::abs(p1) + std::abs(p2) + r);
    return std::min({p0, p1, p2}) > r + slack || std::max({p0, p1, p2}) < -r - slack;
  };
  for (int k = 0; k < 3; ++k) {
    std::array<double, 3> axis{0, 0, 0};
    axis[k] = 1;
    if (separated(axis)) return false;
  }
  const std::array<std::array<double, 3>, 3> edges = {sub(v[1], v[0]), sub(v[2], v[1]),
                                                      sub(v[0], v[2])};
  if (separated(cross3(edges[0], edges[1]))) return false;
  for (const auto& e : edges)
    for (int k = 0; k < 3; ++k) {
      std::array<double, 3> unit{0, 0, 0};
      unit[k] = 1;
      if (separated(cross3(e, unit))) return false;
    }
  return true;
}

// AABB-tree traversal for one long face f: lists the faces that share no vertex with f and whose
// triangle meets f's (exact predicates). Faces sharing a vertex are tested through f's one-ring:
// an exact triangle-triangle test at the shared vertex is degenerate and slow (the filter falls
// back to exact arithmetic), and a spot volume's fan shares its apex among thousands of faces.
class DisjointFaceLister {
 public:
  using Node = CGAL::AABB_node<TreeTraits>;
  DisjointFaceLister(const SurfaceMesh& sm, FaceIndex f, std::vector<FaceIndex>* out)
      : sm_(sm), f_(f), out_(out) {
    int k = 0;
    for (const auto v : CGAL::vertices_around_face(sm.halfedge(f), sm)) {
      verts_[k] = v;
      const auto& p = sm.point(v);
      tri_[k] = {p.x(), p.y(), p.z()};
      ++k;
    }
  }
  bool go_further() const { return true; }
  bool do_intersect(const Kernel::Triangle_3&, const Node& node) const {
    return triangle_may_meet_box(tri_, node.bbox());
  }
  void intersection(const Kernel::Triangle_3& query, const Primitive& primitive) {
    const FaceIndex g = primitive.id();
    if (g == f_) return;
    std::array<SurfaceMesh::Vertex_index, 3> gv;
    int k = 0;
    for (const auto v : CGAL::vertices_around_face(sm_.halfedge(g), sm_)) {
      if (v == verts_[0] || v == verts_[1] || v == verts_[2]) return;
      gv[k++] = v;
    }
    if (!triangle_may_meet_box(tri_, CGAL::Polygon_mesh_processing::face_bbox(g, sm_))) return;
    if (CGAL::do_intersect(
            query, Kernel::Triangle_3(sm_.point(gv[0]), sm_.point(gv[1]), sm_.point(gv[2]))))
      out_->push_back(g);
  }

 private:
  const SurfaceMesh& sm_;
  FaceIndex f_;
  std::vector<FaceIndex>* out_;
  std::array<SurfaceMesh::Vertex_index, 3> verts_;
  std::array<std::array<double, 3>, 3> tri_;
};

// ---- Hubs: vertices shared by many faces
// ---------------------------------------------------------
//
// Every face around a vertex h contains h, so their boxes all overlap there and any box sweep tests
// all deg(h)² pairs: a spot volume's apex (4W faces), a directional cap's centre, or a hostile mesh
// whose faces all share one vertex. Faces around such a hub are tested through their directions
// from h instead. Seen from h, the face (h, a, b) is the great-circle arc from a's direction to
// b's; every point of the face other than h lies along a direction of that arc. So
//  - two faces around h meet somewhere other than h only if their arcs meet;
//  - a face g away from h meets (h, a, b) only if the cone of directions from h to g meets the arc,
//    or if g contains h itself.
// Boxes around arcs and cones on the unit sphere are small where the faces' boxes are huge, and
// every candidate they give goes through CGAL's exact pair test.

using SphereBox = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::uint32_t>;

struct Dir {
  double x, y, z;
};

Dir direction(const Kernel::Point_3& from, const Kernel::Point_3& to) {
  const double dx = to.x() - from.x(), dy = to.y() - from.y(), dz = to.z() - from.z();
  const double n = std::sqrt(dx * dx + dy * dy + dz * dz);
  return n > 0 ? Dir{dx / n, dy / n, dz / n} : Dir{0, 0, 0};
}

// Grows `lo`/`hi` to hold a conservative box of the minor great-circle arc from u to w (unit
// vectors): the arc lies in the triangle of u, w and the point where the tangents at u and w meet,
// (u + w) / (1 + u·w). Arcs close to a half circle (or a zero direction) get the whole sphere.
void add_arc(const Dir& u, const Dir& w, double lo[3], double hi[3]) {
  const double uw = u.x * w.x + u.y * w.y + u.z * w.z;
  const bool zero = (u.x == 0 && u.y == 0 && u.z == 0) || (w.x == 0 && w.y == 0 && w.z == 0);
  if (zero || 1 + uw < 1e-3) {
    for (int k = 0; k < 3; ++k) lo[k] = -1.5, hi[k] = 1.5;
    return;
  }
  const double s = 1 / (1 + uw);
  const double pts[3][3] = {
      {u.x, u.y, u.z}, {w.x, w.y, w.z}, {(u.x + w.x) * s, (u.y + w.y) * s, (u.z + w.z) * s}};
  for (const auto& p : pts)
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
}

SphereBox make_sphere_box(double lo[3], double hi[3], std::uint32_t info) {
  constexpr double kSlack = 1e-7;  // the rounding of the directions, many times over
  for (int k = 0; k < 3; ++k) lo[k] -= kSlack, hi[k] += kSlack;
  return SphereBox(lo, hi, info);
}

double det3(const Dir& a, const Dir& b, const Dir& c) {
  return a.x * (b.y * c.z - b.z * c.y) - a.y * (b.x * c.z - b.z * c.x) +
         a.z * (b.x * c.y - b.y * c.x);
}

// The box of the cone of directions from h to triangle (u1, u2, u3) (their directions): its three
// edge arcs, plus each axis point ±e_k the cone contains (where a coordinate peaks inside).
SphereBox cone_box(const Dir u[3], std::uint32_t info) {
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (int i = 0; i < 3; ++i) add_arc(u[i], u[(i + 1) % 3], lo, hi);
  const double d = det3(u[0], u[1], u[2]);
  for (int k = 0; k < 3; ++k)
    for (const double sign : {-1.0, 1.0}) {
      Dir e{0, 0, 0};
      (k == 0 ? e.x : k == 1 ? e.y : e.z) = sign;
      // e = a·u1 + b·u2 + c·u3 with a, b, c ≥ 0: by Cramer, the three triple products with e
      // share the sign of det(u1, u2, u3). The tolerance covers their rounding, so a point on the
      // cone's boundary counts as inside.
      const double a = det3(e, u[1], u[2]), b = det3(u[0], e, u[2]), c = det3(u[0], u[1], e);
      constexpr double tol = 1e-12;
      const bool inside = (a >= -tol && b >= -tol && c >= -tol && d >= -tol) ||
                          (a <= tol && b <= tol && c <= tol && d <= tol);
      if (inside) lo[k] = std::min(lo[k], sign), hi[k] = std::max(hi[k], sign);
    }
  return make_sphere_box(lo, hi, info);
}

// Hubs: vertices around which the faces are too many for pairwise boxes: degree ≥ min_degree and
// degree² ≥ faces. A hub pass costs about one pass over the faces, and there are at most 3·√faces
// hubs, so the whole stays below quadratic.
std::vector<SurfaceMesh::Vertex_index> find_hubs(const SurfaceMesh& sm, std::size_t min_degree) {
  const double nf = static_cast<double>(sm.number_of_faces());
  std::vector<SurfaceMesh::Vertex_index> hubs;
  for (const auto v : sm.vertices()) {
    const std::size_t degree = sm.degree(v);
    const double d = static_cast<double>(degree);
    if (degree >= min_degree && d * d >= nf) hubs.push_back(v);
  }
  return hubs;
}

// Candidate pairs for the faces around hub h: arcs against arcs, and arcs against the cones of the
// faces away from h (processed in chunks to bound the memory of the boxes).
void hub_candidates(const SurfaceMesh& sm, SurfaceMesh::Vertex_index h,
                    std::vector<std::pair<FaceIndex, FaceIndex>>* candidates) {
  const Kernel::Point_3& ph = sm.point(h);
  std::vector<SphereBox> arcs;
  std::vector<char> around(sm.number_of_faces(), 0);
  CGAL::Bbox_3 reach;  // the box of the faces around h
  for (const FaceIndex f : CGAL::faces_around_target(sm.halfedge(h), sm)) {
    if (f == SurfaceMesh::null_face()) continue;
    around[f.idx()] = 1;
    reach += PMP::face_bbox(f, sm);
    Dir d[2];
    int k = 0;
    for (const auto v : CGAL::vertices_around_face(sm.halfedge(f), sm))
      if (v != h && k < 2) d[k++] = direction(ph, sm.point(v));
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    add_arc(d[0], d[1], lo, hi);
    arcs.push_back(make_sphere_box(lo, hi, static_cast<std::uint32_t>(f.idx())));
  }
  const auto add = [candidates](const SphereBox& a, const SphereBox& b) {
    candidates->emplace_back(FaceIndex(a.info()), FaceIndex(b.info()));
  };
  CGAL::box_self_intersection_d(arcs.begin(), arcs.end(), add);

  const Kernel::Point_3 hub_point = ph;
  std::vector<SphereBox> cones;
  constexpr std::size_t kChunk = 1 << 20;
  const auto flush = [&] {
    if (cones.empty()) return;
    CGAL::box_intersection_d(arcs.begin(), arcs.end(), cones.begin(), cones.end(), add);
    cones.clear();
  };
  for (const FaceIndex g : sm.faces()) {
    if (around[g.idx()] || !CGAL::do_overlap(PMP::face_bbox(g, sm), reach)) continue;
    const auto hg = sm.halfedge(g);
    const Kernel::Point_3 &a = sm.point(sm.source(hg)), &b = sm.point(sm.target(hg)),
                          &c = sm.point(sm.target(sm.next(hg)));
    if (CGAL::do_intersect(Kernel::Triangle_3(a, b, c), hub_point)) {
      // g passes through h: it meets every face around h there.
      for (const SphereBox& arc : arcs) candidates->emplace_back(FaceIndex(arc.info()), g);
      continue;
    }
    const Dir u[3] = {direction(ph, a), direction(ph, b), direction(ph, c)};
    cones.push_back(cone_box(u, static_cast<std::uint32_t>(g.idx())));
    if (cones.size() == kChunk) flush();
  }
  flush();
}

bool faces_intersect(const SurfaceMesh& sm, FaceIndex f, FaceIndex g) {
  const Kernel kernel;
  return PMP::internal::do_faces_intersect<Kernel>(
      sm.halfedge(f), sm.halfedge(g), sm, sm.points(), kernel.construct_segment_3_object(),
      kernel.construct_triangle_3_object(), kernel.do_intersect_3_object());
}

// Pairs among `faces` (none of them around a hub) that intersect other than along a shared edge or
// vertex (CGAL's definition).
//
// CGAL's sweep over face bounding boxes tests every pair of overlapping boxes. Long faces (a
// directional volume's walls, or slivers in a hostile mesh) have boxes that overlap a large part
// of the mesh, and the sweep turns quadratic. So faces whose box is longer than `long_face_ratio`
// times the median are swept among themselves, and tested against the short ones through an AABB
// tree of those, whose traversal prunes with the triangle itself; each candidate then goes through
// the same pair test CGAL's sweep uses.
std::vector<std::pair<FaceIndex, FaceIndex>> sweep_pairs(const SurfaceMesh& sm,
                                                         const std::vector<FaceIndex>& faces,
                                                         double long_face_ratio,
                                                         std::size_t limit) {
  const std::size_t nf = faces.size();
  std::vector<double> extent(sm.number_of_faces(), 0.0);
  std::vector<double> sorted;
  sorted.reserve(nf);
  for (FaceIndex f : faces) {
    const CGAL::Bbox_3 box = PMP::face_bbox(f, sm);
    extent[f.idx()] =
        std::max({box.xmax() - box.xmin(), box.ymax() - box.ymin(), box.zmax() - box.zmin()});
    sorted.push_back(extent[f.idx()]);
  }
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(nf / 2),
                   sorted.end());
  const double threshold = long_face_ratio * (nf ? sorted[nf / 2] : 0.0);
  std::vector<FaceIndex> short_faces, long_faces;
  std::vector<char> is_long(sm.number_of_faces(), 0);
  for (FaceIndex f : faces) {
    if (extent[f.idx()] > threshold) {
      long_faces.push_back(f);
      is_long[f.idx()] = 1;
    } else {
      short_faces.push_back(f);
    }
  }

  // Short against short, and long against long: CGAL's sweep.
  std::vector<std::pair<FaceIndex, FaceIndex>> pairs;
  PMP::self_intersections<CGAL::Parallel_if_available_tag>(
      short_faces, sm, std::back_inserter(pairs), CGAL::parameters::maximum_number(limit));
  if (long_faces.empty() || pairs.size() >= limit) return pairs;
  PMP::self_intersections<CGAL::Parallel_if_available_tag>(
      long_faces, sm, std::back_inserter(pairs), CGAL::parameters::maximum_number(limit));
  if (short_faces.empty() || pairs.size() >= limit) return pairs;

  // Long against short: each long face through an AABB tree of the short ones.
  std::vector<char> in_subset(sm.number_of_faces(), 0);
  for (FaceIndex f : faces) in_subset[f.idx()] = 1;
  Tree tree(short_faces.begin(), short_faces.end(), sm);
  tree.build();
  std::mutex found_mutex;
  tbb::parallel_for(std::size_t{0}, long_faces.size(), [&](std::size_t i) {
    const FaceIndex f = long_faces[i];
    const auto h = sm.halfedge(f);
    const Kernel::Triangle_3 triangle(sm.point(sm.source(h)), sm.point(sm.target(h)),
                                      sm.point(sm.target(sm.next(h))));
    std::vector<FaceIndex> hits;
    DisjointFaceLister lister(sm, f, &hits);
    tree.traversal(triangle, lister);
    // Faces sharing a vertex with f: CGAL's pair test (opposite edges against the triangles).
    for (const auto v : CGAL::vertices_around_face(h, sm))
      for (const FaceIndex g : CGAL::faces_around_target(sm.halfedge(v), sm))
        if (g != SurfaceMesh::null_face() && !is_long[g.idx()] && in_subset[g.idx()])
          hits.push_back(g);
    std::sort(hits.begin(), hits.end());
    hits.erase(std::unique(hits.begin(), hits.end()), hits.end());
    for (const FaceIndex g : hits) {
      if (!faces_intersect(sm, f, g)) continue;
      const std::lock_guard<std::mutex> lock(found_mutex);
      if (pairs.size() < limit) pairs.emplace_back(std::min(f, g), std::max(f, g));
    }
  });
  return pairs;
}

// Pairs of faces that intersect other than along a shared edge or vertex: the faces around hubs
// through their directions from the hub, the others through the box sweep.
std::vector<std::pair<FaceIndex, FaceIndex>> intersecting_pairs(const SurfaceMesh& sm,
                                                                double long_face_ratio,
                                                                std::size_t min_hub_degree,
                                                                std::size_t limit) {
  const std::vector<SurfaceMesh::Vertex_index> hubs = find_hubs(sm, min_hub_degree);
  std::vector<char> hubbed(sm.number_of_faces(), 0);
  for (const auto h : hubs)
    for (const FaceIndex f : CGAL::faces_around_target(sm.halfedge(h), sm))
      if (f != SurfaceMesh::null_face()) hubbed[f.idx()] = 1;
  std::vector<FaceIndex> rest;
  for (const FaceIndex f : sm.faces())
    if (!hubbed[f.idx()]) rest.push_back(f);
  std::vector<std::pair<FaceIndex, FaceIndex>> pairs =
      sweep_pairs(sm, rest, long_face_ratio, limit);

  std::vector<std::pair<FaceIndex, FaceIndex>> candidates;
  for (const auto h : hubs) {
    if (pairs.size() >= limit) break;
    candidates.clear();
    hub_candidates(sm, h, &candidates);
    for (auto& [f, g] : candidates)
      if (g < f) std::swap(f, g);
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    std::mutex found_mutex;
    tbb::parallel_for(std::size_t{0}, candidates.size(), [&](std::size_t i) {
      const auto [f, g] = candidates[i];
      if (f == g || !faces_intersect(sm, f, g)) return;
      const std::lock_guard<std::mutex> lock(found_mutex);
      if (pairs.size() < limit) pairs.emplace_back(f, g);
    });
  }
  return pairs;
}

}  // namespace

CgalChecks cgal_checks(const Mesh& mesh, bool closed, std::size_t max_pairs, double long_face_ratio,
                       std::size_t min_hub_degree) {
  CgalChecks out;
  SurfaceMesh sm;
  if (!to_surface_mesh(mesh, &sm, &out.why_not)) return out;
  out.built = true;

  std::vector<std::pair<FaceIndex, FaceIndex>> pairs =
      intersecting_pairs(sm, long_face_ratio, min_hub_degree, kMaxPairs);
  for (auto& [f, g] : pairs)
    if (g < f) std::swap(f, g);
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());  // found from two hubs
  out.intersecting_pairs = pairs.size();
  out.pairs_truncated = pairs.size() >= kMaxPairs;
  for (std::size_t i = 0; i < pairs.size() && i < max_pairs; ++i)
    out.first_pairs.emplace_back(static_cast<std::uint32_t>(pairs[i].first.idx()),
                                 static_cast<std::uint32_t>(pairs[i].second.idx()));

  auto component = sm.add_property_map<FaceIndex, std::size_t>("f:lightvol_cc", 0).first;
  out.components = PMP::connected_components(sm, component);
  if (closed && pairs.empty()) {
    out.ran_volume_test = true;
    out.bounds_a_volume = PMP::does_bound_a_volume(sm);
  }
  return out;
}

bool cgal_does_self_intersect(const Mesh& mesh, double long_face_ratio,
                              std::size_t min_hub_degree) {
  SurfaceMesh sm;
  std::string why_not;
  if (!to_surface_mesh(mesh, &sm, &why_not)) return true;
  return !intersecting_pairs(sm, long_face_ratio, min_hub_degree, 1).empty();
}

bool cgal_pmp_does_self_intersect(const Mesh& mesh) {
  SurfaceMesh sm;
  std::string why_not;
  if (!to_surface_mesh(mesh, &sm, &why_not)) return true;
  return PMP::does_self_intersect<CGAL::Parallel_if_available_tag>(sm);
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> cgal_pmp_self_intersections(const Mesh& mesh) {
  SurfaceMesh sm;
  std::string why_not;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
  if (!to_surface_mesh(mesh, &sm, &why_not)) return out;
  std::vector<std::pair<FaceIndex, FaceIndex>> pairs;
  PMP::self_intersections<CGAL::Parallel_if_available_tag>(sm, std::back_inserter(pairs));
  for (const auto& [f, g] : pairs)
    out.emplace_back(static_cast<std::uint32_t>(std::min(f, g).idx()),
                     static_cast<std::uint32_t>(std::max(f, g).idx()));
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

bool cgal_bounds_a_volume(const Mesh& mesh) {
  SurfaceMesh sm;
  std::string why_not;
  if (!to_surface_mesh(mesh, &sm, &why_not)) return false;
  return PMP::does_bound_a_volume(sm);
}

}  // namespace lightvol::detail
