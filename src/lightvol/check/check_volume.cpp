// check_volume: the linear checks, then the self-intersection and bounds-a-volume tests
// (lightvol's, detail/exact_checks.cpp, or CGAL's, detail/cgal_checks.cpp), and the
// non-self-nesting verdict they give without a light.
#include <algorithm>

#include <lightvol/check/check.h>
#include <lightvol/check/detail/cgal_checks.h>
#include <lightvol/check/detail/exact_checks.h>
#include <lightvol/check/detail/linear_checks.h>
#include <lightvol/core/check.h>
#include <lightvol/core/limits.h>

namespace lightvol {

using detail::make_offender;
using detail::passed;
using detail::skipped;

std::uint64_t check_memory_bytes(std::uint64_t vertices, std::uint64_t triangles, bool with_light,
                                 const CheckOptions& options) {
  const bool exact = !with_light || options.cgal_with_light;
  const std::uint64_t per_triangle = !exact                                    ? 12
                                     : options.engine == CheckEngine::lightvol ? 64
                                                                               : 256;
  return process_base_bytes() + 24 * vertices + per_triangle * triangles;
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
    const std::size_t max_pairs = static_cast<std::size_t>(std::max(options.max_offenders, 1));
    const detail::CgalChecks c =
        options.engine == CheckEngine::cgal
            ? detail::cgal_checks(mesh, passed(report, kCheckClosed), max_pairs)
            : detail::exact_checks(mesh, passed(report, kCheckClosed), max_pairs);
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
