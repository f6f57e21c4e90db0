// A check report: names of statuses and proofs, validity, and the one-line first failure.
#include <sstream>

#include <lightvol/check/check.h>

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

}  // namespace lightvol
