// The only translation unit that includes CGAL (slow to compile): the flat Mesh becomes a
// CGAL::Surface_mesh here and nowhere else.
#include <lightvol/check/cgal_checks.h>

#include <algorithm>
#include <iterator>

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

}  // namespace

CgalChecks cgal_checks(const Mesh& mesh, bool closed, std::size_t max_pairs) {
  CgalChecks out;
  SurfaceMesh sm;
  if (!to_surface_mesh(mesh, &sm, &out.why_not)) return out;
  out.built = true;

  std::vector<std::pair<FaceIndex, FaceIndex>> pairs;
  PMP::self_intersections<CGAL::Parallel_if_available_tag>(
      sm, std::back_inserter(pairs), CGAL::parameters::maximum_number(kMaxPairs));
  std::sort(pairs.begin(), pairs.end());
  out.intersecting_pairs = pairs.size();
  out.pairs_truncated = pairs.size() >= kMaxPairs;
  for (std::size_t i = 0; i < pairs.size() && i < max_pairs; ++i) {
    auto [f, g] = pairs[i];
    if (g < f) std::swap(f, g);
    out.first_pairs.emplace_back(static_cast<std::uint32_t>(f.idx()),
                                 static_cast<std::uint32_t>(g.idx()));
  }

  auto component = sm.add_property_map<FaceIndex, std::size_t>("f:lightvol_cc", 0).first;
  out.components = PMP::connected_components(sm, component);
  if (closed && pairs.empty()) {
    out.ran_volume_test = true;
    out.bounds_a_volume = PMP::does_bound_a_volume(sm);
  }
  return out;
}

bool cgal_does_self_intersect(const Mesh& mesh) {
  SurfaceMesh sm;
  std::string why_not;
  if (!to_surface_mesh(mesh, &sm, &why_not)) return true;
  return PMP::does_self_intersect<CGAL::Parallel_if_available_tag>(sm);
}

}  // namespace lightvol::detail
