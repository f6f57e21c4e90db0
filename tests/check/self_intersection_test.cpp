// lightvol's self-intersection and bounds-a-volume tests (detail/exact_checks.h) against CGAL's:
// the same refusals, the same pairs as PMP::self_intersections, the same connected components and
// bounds-a-volume verdicts, on generated meshes made to touch, fold and cross (on a grid of
// quarter units, so that faces are exactly coplanar, edges exactly cross and vertices exactly
// coincide), on volumes built from depth maps, on the bundled scene and on the mesh fuzz corpus.
// LIGHTVOL_SI_MESHES=N (default 300) sets the number of generated meshes
// (tests/check/self_intersection_all.sh runs 10,000).
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/check/check.h>
#include <lightvol/check/detail/cgal_checks.h>
#include <lightvol/check/detail/exact_checks.h>
#include <lightvol/io/mesh_reader.h>
#include <lightvol/volume/static_volume.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

using Pairs = std::vector<std::pair<std::uint32_t, std::uint32_t>>;

std::uint32_t add_vertex(Mesh& m, double x, double y, double z) {
  m.positions.insert(m.positions.end(),
                     {static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)});
  return static_cast<std::uint32_t>(m.num_vertices() - 1);
}

void add_face(Mesh& m, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  m.indices.insert(m.indices.end(), {a, b, c});
}

// A closed "pillow" over an n×n grid: the top's interior raised, the bottom's interior lowered, the
// two sharing the boundary ring at z = 0; outward, edge-manifold, one component.
Mesh pillow(int n, std::mt19937& rng, double x0 = 0, double y0 = 0, double z0 = 0,
            double scale = 1) {
  Mesh m;
  std::uniform_int_distribution<int> height(1, 8);
  std::vector<std::uint32_t> top((n + 1) * (n + 1)), bottom((n + 1) * (n + 1));
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const bool edge = i == 0 || j == 0 || i == n || j == n;
      const double x = x0 + scale * i, y = y0 + scale * j;
      top[j * (n + 1) + i] = add_vertex(m, x, y, z0 + (edge ? 0 : scale * 0.25 * height(rng)));
      bottom[j * (n + 1) + i] =
          edge ? top[j * (n + 1) + i] : add_vertex(m, x, y, z0 - scale * 0.25 * height(rng));
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      if ((i == n - 1 && j == 0) || (i == 0 && j == n - 1)) {
        // The other diagonal, which would join two boundary vertices (an edge of four faces).
        add_face(m, top[a], top[b], top[c]);
        add_face(m, top[b], top[d], top[c]);
        add_face(m, bottom[a], bottom[c], bottom[b]);
        add_face(m, bottom[b], bottom[c], bottom[d]);
        continue;
      }
      add_face(m, top[a], top[b], top[d]);
      add_face(m, top[a], top[d], top[c]);
      add_face(m, bottom[a], bottom[d], bottom[b]);
      add_face(m, bottom[a], bottom[c], bottom[d]);
    }
  return m;
}

// A double cone: k ring vertices, an apex above and a centre below, each of degree k (hubs for
// k ≥ 33).
Mesh double_cone(int k, double apex, double centre) {
  Mesh m;
  const std::uint32_t top = add_vertex(m, 0, 0, apex), bottom = add_vertex(m, 0, 0, centre);
  for (int i = 0; i < k; ++i) {
    const double a = 2 * M_PI * i / k;
    add_vertex(m, 2 * std::cos(a), 2 * std::sin(a), 0);
  }
  for (int i = 0; i < k; ++i) {
    const std::uint32_t u = 2 + i, v = 2 + (i + 1) % k;
    add_face(m, top, u, v);
    add_face(m, bottom, v, u);
  }
  return m;
}

void append(Mesh& m, const Mesh& other, bool flip) {
  const std::uint32_t base = static_cast<std::uint32_t>(m.num_vertices());
  m.positions.insert(m.positions.end(), other.positions.begin(), other.positions.end());
  for (std::size_t t = 0; t < other.num_triangles(); ++t) {
    const auto [a, b, c] = other.triangle(t);
    if (flip)
      add_face(m, base + a, base + c, base + b);
    else
      add_face(m, base + a, base + b, base + c);
  }
}

// Moves that make touching, coplanar, crossing and near-touching faces: a coordinate set to a
// quarter unit, a vertex moved onto another, a region flattened, a nudge of a float ulp or two.
void perturb(Mesh& m, std::mt19937& rng, int moves) {
  const std::size_t nv = m.num_vertices();
  std::uniform_int_distribution<std::size_t> vertex(0, nv - 1);
  std::uniform_int_distribution<int> kind(0, 5), quarter(-8, 8), axis(0, 2);
  for (int k = 0; k < moves; ++k) {
    const std::size_t v = vertex(rng);
    float* p = &m.positions[3 * v];
    switch (kind(rng)) {
      case 0:
        p[axis(rng)] = 0.25f * static_cast<float>(quarter(rng));
        break;
      case 1: {
        const std::size_t w = vertex(rng);
        for (int a = 0; a < 3; ++a) p[a] = m.positions[3 * w + a];
        break;
      }
      case 2: {
        const int a = axis(rng);
        p[a] = std::nextafter(p[a], quarter(rng) > 0 ? INFINITY : -INFINITY);
        break;
      }
      case 3: {  // onto the middle of another vertex's neighbour: an edge through a vertex
        const std::size_t w = vertex(rng), u = vertex(rng);
        for (int a = 0; a < 3; ++a) p[a] = 0.5f * (m.positions[3 * w + a] + m.positions[3 * u + a]);
        break;
      }
      case 4: {  // flatten: every vertex with z within a quarter of this one's
        const float z = p[2];
        for (std::size_t w = 0; w < nv; ++w)
          if (std::abs(m.positions[3 * w + 2] - z) <= 0.25f) m.positions[3 * w + 2] = z;
        break;
      }
      default:
        p[axis(rng)] += 0.25f * static_cast<float>(quarter(rng));
        break;
    }
  }
}

// Generated mesh number `index`: pillows, double cones and pairs of shells, perturbed.
Mesh generated(int index) {
  std::mt19937 rng(static_cast<std::uint32_t>(index) * 2654435761u + 12345u);
  std::uniform_int_distribution<int> shape(0, 3), size(2, 5), moves(0, 4), flip(0, 1),
      offset(-6, 6), sides(33, 48);
  Mesh m;
  switch (shape(rng)) {
    case 0:
      m = pillow(size(rng), rng);
      break;
    case 1:
      m = double_cone(sides(rng), 0.25 * offset(rng), -0.25 * (offset(rng) + 7));
      break;
    case 2: {  // two shells: apart, touching, overlapping, or one inside the other
      m = pillow(size(rng), rng);
      const bool inside = flip(rng) != 0;
      const Mesh other =
          inside ? pillow(2, rng, 1.25, 1.25, 0, 0.25)
                 : pillow(size(rng), rng, 0.5 * offset(rng), 0.5 * offset(rng), 0.25 * offset(rng));
      append(m, other, flip(rng) != 0);
      break;
    }
    default: {  // a pillow and a double cone
      m = pillow(size(rng), rng);
      append(m, double_cone(sides(rng), 1, -1), false);
      break;
    }
  }
  perturb(m, rng, moves(rng));
  return m;
}

bool cgal_can_run(const Mesh& mesh, bool* closed) {
  const CheckReport r = check_volume_linear(mesh, nullptr);
  const auto passed = [&](std::string_view name) {
    const CheckResult* c = r.find(name);
    return c && c->status == CheckStatus::passed;
  };
  *closed = passed(kCheckClosed);
  return passed(kCheckIndices) && passed(kCheckManifold) && passed(kCheckOriented);
}

struct Outcome {
  bool ran = false;  // CGAL could take the mesh
  bool intersecting = false;
  std::size_t components = 0;
};

// lightvol's tests against CGAL's, on one mesh CGAL can take (edge-manifold, oriented, one fan
// at every vertex).
Outcome expect_same_as_cgal(const Mesh& mesh, const std::string& what) {
  Outcome out;
  bool closed = false;
  if (!cgal_can_run(mesh, &closed)) return out;
  constexpr std::size_t kAll = 100000;
  const detail::CgalChecks mine = detail::exact_checks(mesh, closed, kAll);
  const detail::CgalChecks theirs = detail::cgal_checks(mesh, closed, kAll);
  EXPECT_EQ(mine.built, theirs.built) << what;
  EXPECT_EQ(mine.why_not, theirs.why_not) << what;
  if (!mine.built || !theirs.built) return out;
  out.ran = true;
  out.components = mine.components;
  const Pairs oracle = detail::cgal_pmp_self_intersections(mesh);
  if (oracle.size() < 10000) {
    EXPECT_EQ(mine.first_pairs, oracle) << what;
    EXPECT_EQ(mine.intersecting_pairs, oracle.size()) << what;
  } else {
    EXPECT_TRUE(mine.pairs_truncated) << what;
  }
  EXPECT_EQ(mine.components, theirs.components) << what;
  EXPECT_EQ(mine.ran_volume_test, closed && oracle.empty()) << what;
  if (mine.ran_volume_test && theirs.ran_volume_test) {
    EXPECT_EQ(mine.bounds_a_volume, theirs.bounds_a_volume) << what;
  }
  EXPECT_EQ(detail::exact_does_self_intersect(mesh), !oracle.empty()) << what;
  out.intersecting = !oracle.empty();
  return out;
}

int generated_count() {
  const char* n = std::getenv("LIGHTVOL_SI_MESHES");
  return n ? std::atoi(n) : 300;
}

TEST(ExactSelfIntersections, GeneratedMeshesGiveCgalsPairs) {
  const int n = generated_count();
  int intersecting = 0, refused = 0, several = 0;
  for (int i = 0; i < n; ++i) {
    const Mesh m = generated(i);
    const Outcome o = expect_same_as_cgal(m, "generated mesh " + std::to_string(i));
    intersecting += o.intersecting;
    refused += !o.ran;
    several += o.components > 1;
    if (HasFailure()) break;
  }
  // The sample must hold every kind of case.
  EXPECT_GT(intersecting, n / 10);
  EXPECT_GT(n - intersecting - refused, n / 10);
  EXPECT_GT(several, n / 10);
}

// Each kind of pair, made on purpose.
TEST(ExactSelfIntersections, FoldedSharedEdgeAndCrossingFansAreFound) {
  std::mt19937 rng(7);
  Mesh flat = pillow(3, rng);
  // Flatten the top, then push an interior top vertex across its neighbour in the plane: faces
  // sharing an edge fold onto each other (coplanar, same side).
  for (std::size_t v = 0; v < flat.num_vertices(); ++v)
    if (flat.positions[3 * v + 2] > 0) flat.positions[3 * v + 2] = 1;
  expect_same_as_cgal(flat, "flat top");
  EXPECT_FALSE(detail::exact_does_self_intersect(flat));
  Mesh folded = flat;
  for (std::size_t v = 0; v < folded.num_vertices(); ++v)
    if (folded.positions[3 * v + 2] == 1 && folded.positions[3 * v] == 1 &&
        folded.positions[3 * v + 1] == 1)
      folded.positions[3 * v] = 2.5f;
  expect_same_as_cgal(folded, "folded top");
  EXPECT_TRUE(detail::exact_does_self_intersect(folded));

  // A double cone folded flat onto itself: its two hubs meet, and faces sharing a ring edge fold.
  const Mesh through = double_cone(40, -1, -1);  // the two hubs at one point
  expect_same_as_cgal(through, "apex through the base");
  EXPECT_TRUE(detail::exact_does_self_intersect(through));
  const Mesh sound = double_cone(40, 1, -1);
  expect_same_as_cgal(sound, "double cone");
  EXPECT_FALSE(detail::exact_does_self_intersect(sound));
}

// Fans around a vertex, seen from above: every face turns the same way in both, but the second
// winds twice around the vertex (seven steps of 720°/7), so its faces overlap. The engine takes a
// star as embedded (and skips its pairs) only when it winds once; the pairs are CGAL's either way.
Mesh fan(int steps, double turns) {
  Mesh m;
  const std::uint32_t v = add_vertex(m, 0, 0, 0);
  std::vector<std::uint32_t> ring;
  for (int k = 0; k < steps; ++k) {
    const double a = 2 * 3.14159265358979 * turns * k / steps, r = 1 + 0.125 * k;
    ring.push_back(add_vertex(m, r * std::cos(a), r * std::sin(a), 0.0625 * k));
  }
  for (int k = 0; k < steps; ++k) add_face(m, v, ring[k], ring[(k + 1) % steps]);
  return m;
}

TEST(ExactSelfIntersections, FanWindingTwiceIsTestedPairByPair) {
  const Mesh once = fan(7, 1), twice = fan(7, 2);
  const Outcome a = expect_same_as_cgal(once, "fan winding once");
  EXPECT_TRUE(a.ran);
  EXPECT_FALSE(a.intersecting);
  EXPECT_FALSE(detail::exact_does_self_intersect(once));
  const Outcome b = expect_same_as_cgal(twice, "fan winding twice");
  EXPECT_TRUE(b.ran);
  EXPECT_TRUE(b.intersecting);
  EXPECT_TRUE(detail::exact_does_self_intersect(twice));
  // Flat (all in one plane, a neighbour opposite another): embedded, nothing to report.
  Mesh plane = fan(8, 1);
  for (std::size_t i = 2; i < plane.positions.size(); i += 3) plane.positions[i] = 0;
  const Outcome c = expect_same_as_cgal(plane, "flat fan");
  EXPECT_TRUE(c.ran);
  EXPECT_FALSE(c.intersecting);
  // Folded: one neighbour pulled across, so that one face turns the other way.
  Mesh folded = plane;
  folded.positions[3 * 3 + 0] *= -0.25f, folded.positions[3 * 3 + 1] *= -0.25f;
  expect_same_as_cgal(folded, "folded fan");
}

// A single closed shell turned inside out bounds a volume for CGAL (the unbounded one: its
// does_bound_a_volume reads an inward outer level as odd); only the linear "outward" check fails.
// Generated mesh 5892 is a double cone with its apex below its base's centre, moved so that its
// highest vertex is unique; the tetrahedron is the least such shell (one highest vertex, incoming
// edges of three slopes).
TEST(ExactSelfIntersections, InsideOutShellBoundsAVolumeAsForCgal) {
  Mesh tetra;
  add_vertex(tetra, 0, 0, 0);
  add_vertex(tetra, 2, 0, 0);
  add_vertex(tetra, 0, 1, 0);
  add_vertex(tetra, 0.25, 0.5, 1);
  // Outward: (0, 2, 1) is the base seen from below, the others seen from outside.
  add_face(tetra, 0, 2, 1);
  add_face(tetra, 0, 1, 3);
  add_face(tetra, 1, 2, 3);
  add_face(tetra, 2, 0, 3);
  Mesh inside_out = tetra;
  for (std::size_t t = 0; t < inside_out.num_triangles(); ++t)
    std::swap(inside_out.indices[3 * t + 1], inside_out.indices[3 * t + 2]);
  const Mesh cone = generated(5892);
  for (const auto& [mesh, what] : {std::pair<const Mesh*, const char*>{&tetra, "tetrahedron"},
                                   {&inside_out, "inside-out tetrahedron"},
                                   {&cone, "generated mesh 5892"}}) {
    const Outcome o = expect_same_as_cgal(*mesh, what);
    EXPECT_TRUE(o.ran) << what;
    EXPECT_FALSE(o.intersecting) << what;
    EXPECT_EQ(o.components, 1u) << what;
    const detail::CgalChecks mine = detail::exact_checks(*mesh, true, 10);
    EXPECT_TRUE(mine.ran_volume_test) << what;
    EXPECT_TRUE(mine.bounds_a_volume) << what;
    const CheckReport report = check_volume_linear(*mesh, nullptr);
    const CheckResult* outward = report.find(kCheckOutward);
    ASSERT_NE(outward, nullptr);
    EXPECT_EQ(outward->status, mesh == &tetra ? CheckStatus::passed : CheckStatus::failed) << what;
  }
}

// Volumes as build makes them (a spot map with occluders, hubs at the apex, depth steps), sound and
// then with a vertex pushed through the floor.
TEST(ExactSelfIntersections, BuiltVolumesGiveCgalsVerdicts) {
  const Light spot = test::light_from_json(test::spot_json());
  const DepthImage depth = test::make_depth(48, 40, [](int c, int r) {
    if (c >= 10 && c < 20 && r >= 8 && r < 30) return 0.95f;
    if ((c - 34) * (c - 34) + (r - 20) * (r - 20) < 40)
      return 0.9f + 0.001f * static_cast<float>(c);
    return 0.98f;
  });
  Result<Mesh> volume = build_static_volume(spot, depth, {}, "test.exr");
  ASSERT_TRUE(volume.ok());
  expect_same_as_cgal(*volume, "spot volume");
  EXPECT_FALSE(detail::exact_does_self_intersect(*volume));
  Mesh broken = *volume;
  std::mt19937 rng(3);
  for (int k = 0; k < 20; ++k) {
    broken = *volume;
    perturb(broken, rng, 1 + k % 3);
    expect_same_as_cgal(broken, "perturbed spot volume " + std::to_string(k));
  }
  const Light directional = test::light_from_json(test::directional_json());
  Result<Mesh> dir_volume = build_static_volume(directional, depth, {}, "test.exr");
  ASSERT_TRUE(dir_volume.ok());
  expect_same_as_cgal(*dir_volume, "directional volume");
}

// The bundled scene and every mesh of the fuzz corpus that CGAL can take.
TEST(ExactSelfIntersections, BundledAndFuzzCorpusMeshesGiveCgalsVerdicts) {
  const std::filesystem::path source = LIGHTVOL_SOURCE_DIR;
  Result<Mesh> scene = read_mesh((source / "data" / "sponza_crop.ply").string());
  ASSERT_TRUE(scene.ok());
  expect_same_as_cgal(*scene, "sponza_crop.ply");
  static const char* const kExtensions[] = {".ply", ".obj", ".off", ".stl", ".drc", ".glb"};
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("lightvol_si_corpus_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  int read = 0;
  for (const auto& entry :
       std::filesystem::directory_iterator(source / "tests" / "fuzz" / "corpus" / "mesh")) {
    std::ifstream in(entry.path(), std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (bytes.empty()) continue;
    const std::filesystem::path file =
        dir /
        (entry.path().filename().string() + kExtensions[static_cast<unsigned char>(bytes[0]) % 6]);
    std::ofstream(file, std::ios::binary) << bytes.substr(1);
    Result<Mesh> mesh = read_mesh(file.string());
    if (!mesh) continue;
    ++read;
    expect_same_as_cgal(*mesh, entry.path().filename().string());
  }
  std::filesystem::remove_all(dir);
  EXPECT_GT(read, 5);
}

}  // namespace
}  // namespace lightvol
