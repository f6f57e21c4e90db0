// The only translation unit that includes CGAL (slow to compile): the flat Mesh becomes a
// CGAL::Surface_mesh here and nowhere else.
#include <lightvol/check/cgal_checks.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <mutex>

#include <tbb/parallel_for.h>

#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

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

// Faces keep their order, so face i of the Surface_mesh is triangle i of `mesh`.
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
  for (std::size_t t = 0; t < nt; ++t) {
    const auto [a, b, c] = mesh.triangle(t);
    if (out->add_face(vs[a], vs[b], vs[c]) == SurfaceMesh::null_face()) {
      *why_not = "face " + std::to_string(t) +
                 " does not fit a manifold surface (a vertex where separate fans meet, or a "
                 "repeated vertex)";
      return false;
    }
  }
  return true;
}

// Does triangle (a, b, c) meet the box? The separating-axis test (Akenine-Möller) in double
// precision on a slightly inflated box: conservative (never says no to a pair that touches), so
// it only prunes the traversal; the exact test comes after.
bool triangle_may_meet_box(const std::array<std::array<double, 3>, 3>& tri, const CGAL::Bbox_3& box) {
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
    const double r = half[0] * std::abs(axis[0]) + half[1] * std::abs(axis[1]) +
                     half[2] * std::abs(axis[2]);
    const double slack = 1e-9 * (std::abs(p0) + std::abs(p1) + std::abs(p2) + r);
    return std::min({p0, p1, p2}) > r + slack || std::max({p0, p1, p2}) < -r - slack;
  };
  for (int k = 0; k < 3; ++k) {
    std::array<double, 3> axis{0, 0, 0};
    axis[k] = 1;
    if (separated(axis)) return false;
  }
  const std::array<std::array<double, 3>, 3> edges = {sub(v[1], v[0]), sub(v[2], v[1]), sub(v[0], v[2])};
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
    if (CGAL::do_intersect(query, Kernel::Triangle_3(sm_.point(gv[0]), sm_.point(gv[1]),
                                                     sm_.point(gv[2]))))
      out_->push_back(g);
  }

 private:
  const SurfaceMesh& sm_;
  FaceIndex f_;
  std::vector<FaceIndex>* out_;
  std::array<SurfaceMesh::Vertex_index, 3> verts_;
  std::array<std::array<double, 3>, 3> tri_;
};

// Pairs of faces that intersect other than along a shared edge or vertex (CGAL's definition).
//
// CGAL's sweep over face bounding boxes tests every pair of overlapping boxes. A spot volume's fan
// triangles reach from the apex to the border of the grid: their boxes overlap a large part of
// the grid, and the sweep turns quadratic (10^9 pairs at 1024²). So faces whose box is longer
// than `long_face_ratio` times the median are swept among themselves, and tested against the
// short ones through an AABB tree of those, whose traversal prunes with the triangle itself; each
// candidate then goes through the same pair test CGAL's sweep uses.
std::vector<std::pair<FaceIndex, FaceIndex>> intersecting_pairs(const SurfaceMesh& sm,
                                                                double long_face_ratio,
                                                                std::size_t limit) {
  const std::size_t nf = sm.number_of_faces();
  std::vector<double> extent(nf);
  for (FaceIndex f : sm.faces()) {
    const CGAL::Bbox_3 box = PMP::face_bbox(f, sm);
    extent[f.idx()] = std::max({box.xmax() - box.xmin(), box.ymax() - box.ymin(),
                                box.zmax() - box.zmin()});
  }
  std::vector<double> sorted = extent;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(nf / 2), sorted.end());
  const double threshold = long_face_ratio * (nf ? sorted[nf / 2] : 0.0);
  std::vector<FaceIndex> short_faces, long_faces;
  std::vector<char> is_long(nf, 0);
  for (FaceIndex f : sm.faces()) {
    if (extent[f.idx()] > threshold) {
      long_faces.push_back(f);
      is_long[f.idx()] = 1;
    } else {
      short_faces.push_back(f);
    }
  }

  // Short against short, and long against long (a fan's boxes all overlap at the apex, but there
  // are only as many as border edges): CGAL's sweep.
  std::vector<std::pair<FaceIndex, FaceIndex>> pairs;
  PMP::self_intersections<CGAL::Parallel_if_available_tag>(
      short_faces, sm, std::back_inserter(pairs), CGAL::parameters::maximum_number(limit));
  if (long_faces.empty() || pairs.size() >= limit) return pairs;
  PMP::self_intersections<CGAL::Parallel_if_available_tag>(
      long_faces, sm, std::back_inserter(pairs), CGAL::parameters::maximum_number(limit));
  if (short_faces.empty() || pairs.size() >= limit) return pairs;

  // Long against short: each long face through an AABB tree of the short ones.
  Tree tree(short_faces.begin(), short_faces.end(), sm);
  tree.build();
  const Kernel kernel;
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
        if (g != SurfaceMesh::null_face() && !is_long[g.idx()]) hits.push_back(g);
    std::sort(hits.begin(), hits.end());
    hits.erase(std::unique(hits.begin(), hits.end()), hits.end());
    for (const FaceIndex g : hits) {
      if (!PMP::internal::do_faces_intersect<Kernel>(
              h, sm.halfedge(g), sm, sm.points(), kernel.construct_segment_3_object(),
              kernel.construct_triangle_3_object(), kernel.do_intersect_3_object()))
        continue;
      const std::lock_guard<std::mutex> lock(found_mutex);
      if (pairs.size() < limit) pairs.emplace_back(std::min(f, g), std::max(f, g));
    }
  });
  return pairs;
}

}  // namespace

CgalChecks cgal_checks(const Mesh& mesh, bool closed, std::size_t max_pairs,
                       double long_face_ratio) {
  CgalChecks out;
  SurfaceMesh sm;
  if (!to_surface_mesh(mesh, &sm, &out.why_not)) return out;
  out.built = true;

  std::vector<std::pair<FaceIndex, FaceIndex>> pairs = intersecting_pairs(sm, long_face_ratio, kMaxPairs);
  for (auto& [f, g] : pairs)
    if (g < f) std::swap(f, g);
  std::sort(pairs.begin(), pairs.end());
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

bool cgal_does_self_intersect(const Mesh& mesh, double long_face_ratio) {
  SurfaceMesh sm;
  std::string why_not;
  if (!to_surface_mesh(mesh, &sm, &why_not)) return true;
  return !intersecting_pairs(sm, long_face_ratio, 1).empty();
}

}  // namespace lightvol::detail
