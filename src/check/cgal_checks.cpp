// The only translation unit that includes CGAL (slow to compile): the flat Mesh becomes a
// CGAL::Surface_mesh here and nowhere else.
#include <lightvol/check/cgal_checks.h>

#include <algorithm>
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
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

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

// Pairs of faces that intersect other than along a shared edge or vertex (CGAL's definition).
//
// CGAL's sweep over face bounding boxes tests every pair of overlapping boxes. A spot volume's fan
// triangles reach from the apex to the border of the grid: their boxes overlap a large part of
// the grid, and the sweep turns quadratic (10^9 pairs at 1024²). So faces whose box is longer
// than `long_face_ratio` times the median are taken out of the sweep and tested instead against
// an AABB tree of all faces, whose traversal prunes with the triangle itself (exact predicates);
// each candidate then goes through the same pair test CGAL's sweep uses.
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

  std::vector<std::pair<FaceIndex, FaceIndex>> pairs;
  PMP::self_intersections<CGAL::Parallel_if_available_tag>(
      short_faces, sm, std::back_inserter(pairs), CGAL::parameters::maximum_number(limit));
  if (long_faces.empty() || pairs.size() >= limit) return pairs;

  Tree tree(sm.faces().begin(), sm.faces().end(), sm);
  tree.build();
  const Kernel kernel;
  std::mutex found_mutex;
  tbb::parallel_for(std::size_t{0}, long_faces.size(), [&](std::size_t i) {
    const FaceIndex f = long_faces[i];
    const auto h = sm.halfedge(f);
    const Kernel::Triangle_3 triangle(sm.point(sm.source(h)), sm.point(sm.target(h)),
                                      sm.point(sm.target(sm.next(h))));
    std::vector<Primitive::Id> hits;
    tree.all_intersected_primitives(triangle, std::back_inserter(hits));
    for (const FaceIndex g : hits) {
      // Each pair once: a long pair from its lower face.
      if (g == f || (is_long[g.idx()] && g < f)) continue;
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
