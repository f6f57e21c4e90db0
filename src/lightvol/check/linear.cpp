// check_volume_linear: the linear-time checks in report order (faces.cpp, edges.cpp,
// light_proof.cpp hold them), and check_closed_outward on top of it. The mesh is read in four
// parallel passes: the vertices (bounds, vertices at the light), the indices,
// the edges (in chunks of lower vertices) and the faces (volume, degenerate faces, the light's
// sums); offenders are found again by sequential passes only when a check fails.
#include <algorithm>
#include <cmath>
#include <sstream>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <lightvol/check/check.h>
#include <lightvol/check/detail/linear_checks.h>
#include <lightvol/check/topology.h>

namespace lightvol {

using detail::degenerate_check;
using detail::directional_view;
using detail::edge_checks;
using detail::EdgeResults;
using detail::face_pass;
using detail::FaceSums;
using detail::LightView;
using detail::nesting_check_directional;
using detail::nesting_check_point;
using detail::passed;
using detail::point_view;
using detail::scan_vertices;
using detail::skipped;
using detail::t_junction_check;
using detail::VertexScan;

// Long (over 80 lines) on purpose: the checks in report order, each one's result pushed as it
// is made; a straight sequence with the skip rules between them.
CheckReport check_volume_linear(const Mesh& mesh, const Light* light, int max_offenders,
                                double quantization_step) {
  CheckReport report;
  report.vertices = mesh.num_vertices();
  report.triangles = mesh.num_triangles();
  const VertexScan scan = scan_vertices(mesh, light, quantization_step);
  report.bounds = scan.bounds;
  report.quantization_step = quantization_step;

  // Indices first: nothing else can look at a face that names a missing vertex.
  CheckResult indices;
  indices.name = kCheckIndices;
  const std::size_t nv = mesh.num_vertices();
  const bool too_big = mesh.num_triangles() >= (std::size_t{1} << 31);
  const auto out_of_range = [&](std::size_t t) {
    const auto [a, b, c] = mesh.triangle(t);
    return a >= nv || b >= nv || c >= nv;
  };
  indices.count = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, mesh.num_triangles(), 1 << 16), std::uint64_t{0},
      [&](const tbb::blocked_range<std::size_t>& r, std::uint64_t n) {
        for (std::size_t t = r.begin(); t != r.end(); ++t) n += out_of_range(t);
        return n;
      },
      [](std::uint64_t x, std::uint64_t y) { return x + y; });
  for (std::size_t t = 0; t < mesh.num_triangles() && indices.count > 0 &&
                          indices.offenders.size() < static_cast<std::size_t>(max_offenders);
       ++t) {
    if (out_of_range(t)) {
      Offender o;
      o.faces = {static_cast<std::int64_t>(t)};
      indices.offenders.push_back(o);
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

  EdgeResults edges = edge_checks(mesh, max_offenders);
  report.checks.push_back(edges.closed);
  report.checks.push_back(edges.manifold);
  report.checks.push_back(edges.oriented);
  const bool topology = passed(report, kCheckClosed) && passed(report, kCheckManifold) &&
                        passed(report, kCheckOriented);

  // One pass over the faces: the volume, the degenerate faces and the light's sums.
  LightView view;
  if (light && topology) {
    view = light->type == LightType::directional ? directional_view(*light, quantization_step)
           : scan.at_light.size() <= 1           ? point_view(mesh, *light, scan, quantization_step)
                                                 : LightView{};
  }
  const FaceSums sums = face_pass(mesh, view);
  report.volume = sums.det / 6.0;
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
  report.checks.push_back(degenerate_check(mesh, sums.degenerate, max_offenders));
  report.checks.push_back(t_junction_check(mesh, edges, max_offenders));

  if (!light) {
    report.checks.push_back(skipped(kCheckNesting, "no light given (CGAL's proof runs in check)"));
  } else if (!topology) {
    report.checks.push_back(skipped(kCheckNesting, "needs a closed, edge-manifold, oriented mesh"));
  } else if (light->type == LightType::directional) {
    report.checks.push_back(nesting_check_directional(mesh, view, sums, max_offenders, &report));
  } else {
    report.checks.push_back(
        nesting_check_point(mesh, scan, view, sums, quantization_step, max_offenders, &report));
  }
  return report;
}

Status check_closed_outward(const Mesh& mesh, const std::string& what) {
  const CheckReport report = check_volume_linear(mesh, nullptr, 1);
  for (const CheckResult& c : report.checks)
    if (c.status == CheckStatus::failed) return Error{what + ": " + report.first_failure()};
  return {};
}

}  // namespace lightvol
