// lightvol check: is a mesh a sound light volume? Exit 0 valid, 1 invalid, 2 unreadable or bad
// usage.
#include <cstdio>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include <lightvol/check/check.h>
#include <lightvol/io/mesh_reader.h>
#include <lightvol/light/light.h>

#include "commands.h"
#include "progress.h"

namespace lightvol::cli {
namespace {

struct CheckCommandOptions {
  std::string mesh_path;
  std::string light_path;
  bool json = false;
  bool quiet = false;
  bool cgal = false;
  std::string engine = "lightvol";
  int offenders = 5;
};

std::string position_text(const std::array<float, 3>& p) {
  std::ostringstream out;
  out.precision(7);
  out << "(" << p[0] << ", " << p[1] << ", " << p[2] << ")";
  return out.str();
}

// "face 12, vertices 5 6 7; (x, y, z)": the first offender on one line.
std::string offender_text(const std::string& check, const Offender& o) {
  std::ostringstream out;
  if (!o.faces.empty()) {
    out << (o.faces.size() == 1 ? "face" : "faces");
    for (std::int64_t f : o.faces) out << ' ' << f;
  }
  if (!o.vertices.empty()) {
    if (!o.faces.empty()) out << ", ";
    if (check == kCheckTJunctions) {
      out << "vertex " << o.vertices[0] << " " << position_text(o.positions[0]) << " inside edge "
          << o.vertices[1] << "-" << o.vertices[2];
      return out.str();
    }
    const bool edge = o.vertices.size() == 2;
    out << (edge ? "edge " : o.vertices.size() == 1 ? "vertex " : "vertices ");
    for (std::size_t k = 0; k < o.vertices.size(); ++k)
      out << (k ? (edge ? "-" : " ") : "") << o.vertices[k];
    out << " at " << position_text(o.positions[0]);
  }
  return out.str();
}

nlohmann::json report_json(const CheckCommandOptions& o, const CheckReport& r) {
  nlohmann::json checks = nlohmann::json::array();
  for (const CheckResult& c : r.checks) {
    nlohmann::json offenders = nlohmann::json::array();
    for (const Offender& off : c.offenders)
      offenders.push_back(
          {{"faces", off.faces}, {"vertices", off.vertices}, {"positions", off.positions}});
    checks.push_back({{"name", c.name},
                      {"status", c.status == CheckStatus::passed   ? "passed"
                                 : c.status == CheckStatus::failed ? "failed"
                                                                   : "skipped"},
                      {"count", c.count},
                      {"detail", with_flags(c.detail)},
                      {"offenders", offenders}});
  }
  nlohmann::json j = {
      {"mesh", o.mesh_path},
      {"valid", r.valid()},
      {"vertices", r.vertices},
      {"triangles", r.triangles},
      {"volume", r.volume},
      {"bounds", {{"min", r.bounds.min}, {"max", r.bounds.max}}},
      {"nesting_proof", to_string(r.proof)},
      {"quantization_step", r.quantization_step},
      {"checks", checks},
  };
  if (!o.light_path.empty())
    j["light"] = {{"path", o.light_path}, {"sum", r.light_sum}, {"expected", r.light_expected}};
  if (!r.valid()) j["first_failure"] = with_flags(r.first_failure());
  return j;
}

void print_table(const CheckCommandOptions& o, const CheckReport& r) {
  std::printf("%s: %s triangles, %s vertices\n", o.mesh_path.c_str(),
              thousands(r.triangles).c_str(), thousands(r.vertices).c_str());
  std::printf("  %-22s %-7s %9s  %s\n", "check", "result", "count", "first offender / detail");
  for (const CheckResult& c : r.checks) {
    const std::string note = c.status == CheckStatus::failed && !c.offenders.empty()
                                 ? offender_text(c.name, c.offenders.front())
                                 : with_flags(c.detail);
    std::printf("  %-22s %-7s %9s  %s\n", c.name.c_str(), std::string(to_string(c.status)).c_str(),
                thousands(c.count).c_str(), note.c_str());
  }
  std::printf("  volume %.9g, bounds (%.6g, %.6g, %.6g) - (%.6g, %.6g, %.6g)\n", r.volume,
              r.bounds.min[0], r.bounds.min[1], r.bounds.min[2], r.bounds.max[0], r.bounds.max[1],
              r.bounds.max[2]);
  std::printf("  non-self-nesting proof: %s\n", std::string(to_string(r.proof)).c_str());
  if (r.quantization_step > 0)
    std::printf("  positions quantized to a grid of step %.3g (Draco): the checks allow for it\n",
                r.quantization_step);
  for (const CheckResult& c : r.checks)
    if (c.status == CheckStatus::failed)
      std::printf("  %s: %s\n", c.name.c_str(), with_flags(c.detail).c_str());
  std::printf("%s\n", r.valid() ? "valid" : "INVALID");
}

int run_check(const CheckCommandOptions& o) {
  Progress progress(o.quiet || o.json);
  Light light;
  if (!o.light_path.empty()) {
    Result<Light> loaded = load_light(o.light_path);
    if (!loaded) return fail(loaded.error());
    light = *loaded;
  }
  CheckOptions options;
  options.cgal_with_light = o.cgal;
  options.engine = o.engine == "cgal" ? CheckEngine::cgal : CheckEngine::lightvol;
  options.max_offenders = o.offenders;
  progress.begin("reading " + o.mesh_path);
  double quantization_step = 0;
  // The check's memory, from the file's counts, against the budget before the mesh is read.
  MeshWork work;
  work.what = "checking";
  work.bytes = [&](std::uint64_t vertices, std::uint64_t triangles) {
    return check_memory_bytes(vertices, triangles, !o.light_path.empty(), options);
  };
  Result<Mesh> mesh = read_mesh(o.mesh_path, &quantization_step, work);
  if (!mesh) return fail(mesh.error());
  progress.end(thousands(mesh->num_triangles()) + " triangles");

  progress.begin("checking");
  options.quantization_step = quantization_step;
  const CheckReport report = check_volume(*mesh, o.light_path.empty() ? nullptr : &light, options);
  progress.end(report.valid() ? "valid" : "invalid");

  if (o.json) {
    std::printf("%s\n", json_text(report_json(o, report), 2).c_str());
  } else if (!o.quiet) {
    print_table(o, report);
  }
  if (report.valid()) return 0;
  if (o.quiet)
    return fail(Error{o.mesh_path + ": invalid: " + report.first_failure(), ErrorKind::unsound});
  return exit_code(ErrorKind::unsound);
}

}  // namespace

void add_check_command(CLI::App& app, Runner* run) {
  auto o = std::make_shared<CheckCommandOptions>();
  CLI::App* cmd = app.add_subcommand("check", "Check that a mesh is a sound light volume.");
  cmd->footer(
      "Example:\n  lightvol check volume.ply --light light.json\n"
      "Checks: indices, closed, edge-manifold, oriented, outward (volume > 0), non-degenerate,\n"
      "no T-junctions, no self-intersections, bounds a volume, non-self-nesting. With --light the\n"
      "last is proved in linear time from the light (every face seen from the light's side, solid\n"
      "angles or projected areas adding up); without it by CGAL's self-intersection and\n"
      "bounds-a-volume tests. The mesh must be in the light's frame (world space, as built).\n"
      "Formats: .ply .obj .off .stl .drc .glb; identical positions are welded first.\n"
      "Exit 0 valid, 1 invalid, 2 unreadable input or bad usage.");
  cmd->add_option("mesh", o->mesh_path, "Mesh to check")->required();
  cmd->add_option("--light", o->light_path, "Light description (LIGHT.json): linear-time proof");
  cmd->add_flag("--cgal", o->cgal,
                "With --light, also run CGAL's self-intersection and volume tests");
  cmd->add_option("--engine", o->engine,
                  "Self-intersection and bounds-a-volume tests: lightvol's own (parallel) or "
                  "CGAL's Polygon Mesh Processing; same verdicts")
      ->check(CLI::IsMember({"lightvol", "cgal"}))
      ->capture_default_str();
  cmd->add_option("--offenders", o->offenders, "Offenders kept per check")
      ->check(decimal_integer())
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_flag("--json", o->json, "Print the report as JSON on stdout");
  cmd->add_flag("--quiet,-q", o->quiet,
                "No progress and no table: the exit code, and one line on stderr when invalid");
  cmd->callback([o, run] { *run = [o] { return run_check(*o); }; });
}

}  // namespace lightvol::cli
