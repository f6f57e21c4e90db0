// lightvol check: a sound volume passes both ways (light proof and CGAL), and each kind of broken
// volume is rejected with its own named failure, with and without the light.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <lightvol/check/check.h>
#include <lightvol/check/detail/cgal_checks.h>
#include <lightvol/check/detail/linear_checks.h>
#include <lightvol/check/topology.h>
#include <lightvol/export/export.h>
#include <lightvol/volume/static_volume.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

// A 9×7 spot map: floor at window depth 0.98 (≈ 4.3 below the light) with a 3×3 occluder at
// 0.95 (≈ 1.9 below it).
DepthImage occluded_depth() {
  return test::make_depth(
      9, 7, [](int c, int r) { return (c >= 3 && c <= 5 && r >= 2 && r <= 4) ? 0.95f : 0.98f; });
}

Light spot_light() { return test::light_from_json(test::spot_json()); }

Mesh sound_spot_volume() {
  Result<Mesh> mesh = build_static_volume(spot_light(), occluded_depth(), {}, "test.exr");
  EXPECT_TRUE(mesh.ok());
  return *mesh;
}

CheckStatus status_of(const CheckReport& r, std::string_view name) {
  const CheckResult* c = r.find(name);
  EXPECT_NE(c, nullptr) << name;
  return c ? c->status : CheckStatus::skipped;
}

std::uint32_t add_vertex(Mesh& mesh, std::array<float, 3> p) {
  mesh.positions.insert(mesh.positions.end(), p.begin(), p.end());
  return static_cast<std::uint32_t>(mesh.num_vertices() - 1);
}

void set_triangle(Mesh& mesh, std::size_t t, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  mesh.indices[3 * t] = a, mesh.indices[3 * t + 1] = b, mesh.indices[3 * t + 2] = c;
}

// Both ways: with the light (linear proof) and without it (CGAL).
struct BothWays {
  CheckReport with_light, without_light;
};
BothWays check_both(const Mesh& mesh, const Light& light) {
  return {check_volume(mesh, &light), check_volume(mesh, nullptr)};
}

// ---- the sound volumes ------------------------------------------------------------------------

TEST(CheckVolume, SoundSpotVolumePassesBothWays) {
  const Mesh mesh = sound_spot_volume();
  const Light light = spot_light();
  const BothWays r = check_both(mesh, light);
  for (const CheckReport* report : {&r.with_light, &r.without_light}) {
    EXPECT_TRUE(report->valid()) << report->first_failure();
    for (const CheckResult& c : report->checks) {
      EXPECT_EQ(c.status, CheckStatus::passed) << c.name << ": " << c.detail;
      EXPECT_EQ(c.count, 0u) << c.name;
    }
    EXPECT_EQ(report->triangles, 2u * 8 * 6 + 2 * 8 + 2 * 6);
    EXPECT_EQ(report->vertices, 9u * 7 + 1);
    EXPECT_GT(report->volume, 0);
  }
  EXPECT_EQ(r.with_light.proof, NestingProof::solid_angles);
  EXPECT_EQ(r.without_light.proof, NestingProof::cgal);

  // The light is the apex: the grid's solid angles add up to the pyramid through the border
  // texel centres, half-angles atan(tan 30° · 8/9) and atan(tan 30° · 6/7):
  // Ω = 4 asin(sin α sin β).
  const double t30 = std::tan(std::numbers::pi / 6);
  const double alpha = std::atan(t30 * 8 / 9), beta = std::atan(t30 * 6 / 7);
  const double pyramid = 4 * std::asin(std::sin(alpha) * std::sin(beta));
  EXPECT_NEAR(r.with_light.light_expected, pyramid, 1e-6);
  EXPECT_NEAR(r.with_light.light_sum, pyramid, 1e-6);
}

TEST(CheckVolume, SoundDirectionalVolumePassesBothWays) {
  const Light light = test::light_from_json(test::directional_json());
  const DepthImage depth = test::make_depth(
      9, 7, [](int c, int r) { return (c >= 2 && c <= 4 && r >= 1 && r <= 3) ? 0.3f : 0.8f; });
  Result<Mesh> mesh = build_static_volume(light, depth, {}, "test.exr");
  ASSERT_TRUE(mesh.ok());
  const BothWays r = check_both(*mesh, light);
  EXPECT_TRUE(r.with_light.valid()) << r.with_light.first_failure();
  EXPECT_TRUE(r.without_light.valid()) << r.without_light.first_failure();
  EXPECT_EQ(r.with_light.proof, NestingProof::projected_areas);
  // Exits and entries both cover the cap: the texel-centre rectangle of the ortho window,
  // 10·(8/9) by 8·(6/7).
  const double cap = 10.0 * 8 / 9 * 8.0 * 6 / 7;
  EXPECT_NEAR(r.with_light.light_expected, cap, 1e-4);
  EXPECT_NEAR(r.with_light.light_sum, cap, 1e-4);

  // Turned inside out, it fails both as inward and as seen from the wrong side.
  Mesh inverted = *mesh;
  for (std::size_t t = 0; t < inverted.num_triangles(); ++t)
    std::swap(inverted.indices[3 * t + 1], inverted.indices[3 * t + 2]);
  const CheckReport bad = check_volume(inverted, &light);
  EXPECT_EQ(status_of(bad, kCheckOutward), CheckStatus::failed);
  EXPECT_EQ(status_of(bad, kCheckNesting), CheckStatus::failed);
}

TEST(CheckVolume, DirectionalProofToleranceScalesWithTheVolume) {
  // A tilted light with a 0.1-wide window over 10 units of depth (walls 1e4 times taller than
  // wide), and the same at 100 times the size: the rounding tolerance of a projected area grows
  // with the face's edges, not with their square, so both are proved and a dragged vertex is
  // caught in both.
  for (const double scale : {0.01, 1.0}) {
    SCOPED_TRACE(scale);
    const std::string json = R"({"type": "directional", "position": [0, 4, 0],)"
                             R"( "direction": [0.3, -1, 0.2], "up": [0, 0, -1], "ortho": [)" +
                             std::to_string(-5 * scale) + ", " + std::to_string(5 * scale) + ", " +
                             std::to_string(-4 * scale) + ", " + std::to_string(4 * scale) +
                             R"(], "near": 0, "far": )" + std::to_string(1000 * scale) +
                             R"(, "depth": "linear"})";
    const Light light = test::light_from_json(json);
    // The border on the near plane: walls as tall as the near-plane offset (1e-4 at scale 0.01).
    const DepthImage depth = test::make_depth(14, 14, [&](int c, int r) {
      const bool border = c == 0 || r == 0 || c == 13 || r == 13;
      return static_cast<float>((border ? 0.0 : (c + r) % 3 == 0 ? 0.9 : 0.01) * 1000 * scale);
    });
    Result<Mesh> mesh = build_static_volume(light, depth, {}, "test.exr");
    ASSERT_TRUE(mesh.ok());
    const CheckReport sound = check_volume_linear(*mesh, &light);
    EXPECT_TRUE(sound.valid()) << sound.first_failure();
    // Texel (6, 6) dragged across its right neighbours, between (9, 6) and (10, 7).
    const auto p9 = mesh->vertex(6 * 14 + 9), p10 = mesh->vertex(7 * 14 + 10);
    for (int k = 0; k < 3; ++k) mesh->positions[3 * (6 * 14 + 6) + k] = 0.5f * (p9[k] + p10[k]);
    const CheckReport dragged = check_volume_linear(*mesh, &light);
    EXPECT_EQ(status_of(dragged, kCheckNesting), CheckStatus::failed);
  }
}

TEST(CheckVolume, LinearChecksSkipCgal) {
  const Mesh mesh = sound_spot_volume();
  const Light light = spot_light();
  const CheckReport r = check_volume_linear(mesh, &light);
  EXPECT_TRUE(r.valid()) << r.first_failure();
  EXPECT_EQ(r.find(kCheckSelfIntersections), nullptr);
  // Without a light the linear checks cannot prove non-self-nesting.
  const CheckReport none = check_volume_linear(mesh, nullptr);
  EXPECT_FALSE(none.valid());
  EXPECT_EQ(status_of(none, kCheckNesting), CheckStatus::skipped);
}

// An omni light inside a closed box: solid angles add up to 4π; outside it, to 0.
TEST(CheckVolume, OmniLightInsideAndOutsideABox) {
  Mesh box;
  for (int i = 0; i < 8; ++i)
    add_vertex(box, {i & 1 ? 1.f : -1.f, i & 2 ? 1.f : -1.f, i & 4 ? 1.f : -1.f});
  // Outward quads, each split in two.
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    box.indices.insert(box.indices.end(),
                       {std::uint32_t(q[0]), std::uint32_t(q[1]), std::uint32_t(q[2])});
    box.indices.insert(box.indices.end(),
                       {std::uint32_t(q[0]), std::uint32_t(q[2]), std::uint32_t(q[3])});
  }
  Light inside = test::light_from_json(
      R"({"type": "omni", "position": [0.2, -0.3, 0.1], "near": 0.1, "far": 30, "depth": "radial"})");
  const CheckReport r = check_volume(box, &inside);
  EXPECT_TRUE(r.valid()) << r.first_failure();
  EXPECT_NEAR(r.light_sum, 4 * std::numbers::pi, 1e-9);

  Light outside = inside;
  outside.position = {3, 0, 0};
  const CheckReport o = check_volume(box, &outside);
  EXPECT_FALSE(o.valid());
  const CheckResult* nesting = o.find(kCheckNesting);
  ASSERT_NE(nesting, nullptr);
  EXPECT_EQ(nesting->status, CheckStatus::failed);
  EXPECT_EQ(nesting->count, 2u) << nesting->detail;  // the two faces of the x = 1 side face it
}

// ---- each broken kind, with and without the light ----------------------------------------------

class BrokenVolume : public ::testing::Test {
 protected:
  Mesh mesh = sound_spot_volume();
  Light light = spot_light();
  // Grid vertex (col, row) of the 9-wide grid.
  static std::uint32_t grid(int col, int row) { return static_cast<std::uint32_t>(row * 9 + col); }
  // Expects `name` failed both ways and neither report is valid.
  void expect_rejected(std::string_view name) {
    const BothWays r = check_both(mesh, light);
    EXPECT_FALSE(r.with_light.valid());
    EXPECT_FALSE(r.without_light.valid());
    EXPECT_EQ(status_of(r.with_light, name), CheckStatus::failed) << name;
    EXPECT_EQ(status_of(r.without_light, name), CheckStatus::failed) << name;
    with_light = r.with_light;
    without_light = r.without_light;
  }
  CheckReport with_light, without_light;
};

TEST_F(BrokenVolume, OneFaceFlipped) {
  std::swap(mesh.indices[3 * 20 + 1], mesh.indices[3 * 20 + 2]);
  expect_rejected(kCheckOriented);
  const CheckResult* c = with_light.find(kCheckOriented);
  EXPECT_EQ(c->count, 3u);  // all three of its edges
  ASSERT_FALSE(c->offenders.empty());
  EXPECT_EQ(c->offenders.front().faces.size(), 2u);
  EXPECT_TRUE(c->offenders.front().faces[0] == 20 || c->offenders.front().faces[1] == 20);
  EXPECT_EQ(status_of(with_light, kCheckClosed), CheckStatus::passed);
  EXPECT_EQ(status_of(with_light, kCheckNesting), CheckStatus::skipped);
}

TEST_F(BrokenVolume, OneFaceRemoved) {
  const auto [a, b, c] = mesh.triangle(30);
  mesh.indices.erase(mesh.indices.begin() + 3 * 30, mesh.indices.begin() + 3 * 31);
  expect_rejected(kCheckClosed);
  const CheckResult* closed = with_light.find(kCheckClosed);
  EXPECT_EQ(closed->count, 3u);
  // The boundary edges are the removed face's, reversed.
  for (const Offender& o : closed->offenders) {
    ASSERT_EQ(o.vertices.size(), 2u);
    const bool matches = (o.vertices[0] == b && o.vertices[1] == a) ||
                         (o.vertices[0] == c && o.vertices[1] == b) ||
                         (o.vertices[0] == a && o.vertices[1] == c);
    EXPECT_TRUE(matches) << o.vertices[0] << "-" << o.vertices[1];
  }
  EXPECT_EQ(status_of(with_light, kCheckTJunctions), CheckStatus::passed);
  EXPECT_EQ(status_of(with_light, kCheckManifold), CheckStatus::passed);
}

TEST_F(BrokenVolume, TJunction) {
  // Split face 0 = (a, b, c) at the midpoint m of its edge a-b, but not its neighbour across a-b.
  const auto [a, b, c] = mesh.triangle(0);
  const auto pa = mesh.vertex(a), pb = mesh.vertex(b);
  const std::uint32_t m =
      add_vertex(mesh, {(pa[0] + pb[0]) / 2, (pa[1] + pb[1]) / 2, (pa[2] + pb[2]) / 2});
  set_triangle(mesh, 0, a, m, c);
  mesh.indices.insert(mesh.indices.end(), {m, b, c});
  expect_rejected(kCheckTJunctions);
  const CheckResult* t = with_light.find(kCheckTJunctions);
  EXPECT_EQ(t->count, 1u);
  ASSERT_EQ(t->offenders.size(), 1u);
  ASSERT_EQ(t->offenders[0].vertices.size(), 3u);
  EXPECT_EQ(t->offenders[0].vertices[0], m);
  EXPECT_TRUE((t->offenders[0].vertices[1] == b && t->offenders[0].vertices[2] == a) ||
              (t->offenders[0].vertices[1] == a && t->offenders[0].vertices[2] == b));
}

TEST_F(BrokenVolume, VertexDraggedAcrossItsNeighbours) {
  // Grid vertex (2, 3) moved beyond its right neighbours, onto the floor between (5, 3) and (6, 4).
  const auto p5 = mesh.vertex(grid(5, 3)), p6 = mesh.vertex(grid(6, 4));
  const std::uint32_t v = grid(2, 3);
  for (int k = 0; k < 3; ++k) mesh.positions[3 * v + k] = 0.5f * (p5[k] + p6[k]);
  const BothWays r = check_both(mesh, light);
  EXPECT_FALSE(r.with_light.valid());
  EXPECT_FALSE(r.without_light.valid());
  EXPECT_EQ(status_of(r.with_light, kCheckNesting), CheckStatus::failed);
  EXPECT_GT(r.with_light.find(kCheckNesting)->count, 0u);
  EXPECT_EQ(status_of(r.without_light, kCheckSelfIntersections), CheckStatus::failed);
  EXPECT_EQ(status_of(r.without_light, kCheckNesting), CheckStatus::failed);
  // The topology is untouched.
  for (std::string_view name : {kCheckClosed, kCheckManifold, kCheckOriented, kCheckDegenerate})
    EXPECT_EQ(status_of(r.with_light, name), CheckStatus::passed) << name;
}

TEST_F(BrokenVolume, TwoNestedOutwardShells) {
  // A copy scaled by 0.2 about a point 1 below the light: strictly inside, also outward.
  const std::uint32_t n = static_cast<std::uint32_t>(mesh.num_vertices());
  const std::size_t nt = mesh.num_triangles();
  for (std::uint32_t v = 0; v < n; ++v) {
    const auto p = mesh.vertex(v);
    add_vertex(mesh, {0.2f * p[0], 3 + 0.2f * (p[1] - 3), 0.2f * p[2]});
  }
  for (std::size_t t = 0; t < nt; ++t) {
    const auto [a, b, c] = mesh.triangle(t);
    mesh.indices.insert(mesh.indices.end(), {a + n, b + n, c + n});
  }
  const BothWays r = check_both(mesh, light);
  EXPECT_FALSE(r.with_light.valid());
  EXPECT_FALSE(r.without_light.valid());
  EXPECT_EQ(status_of(r.with_light, kCheckNesting), CheckStatus::failed);
  EXPECT_EQ(status_of(r.without_light, kCheckBoundsVolume), CheckStatus::failed);
  EXPECT_EQ(status_of(r.without_light, kCheckNesting), CheckStatus::failed);
  EXPECT_EQ(status_of(r.without_light, kCheckSelfIntersections), CheckStatus::passed);
  EXPECT_EQ(status_of(r.with_light, kCheckOutward), CheckStatus::passed);
}

TEST_F(BrokenVolume, WholeMeshInverted) {
  for (std::size_t t = 0; t < mesh.num_triangles(); ++t)
    std::swap(mesh.indices[3 * t + 1], mesh.indices[3 * t + 2]);
  expect_rejected(kCheckOutward);
  EXPECT_LT(with_light.volume, 0);
  EXPECT_EQ(status_of(with_light, kCheckNesting), CheckStatus::failed);
  // Every grid face now faces the light.
  EXPECT_EQ(with_light.find(kCheckNesting)->count, 2u * 8 * 6);
}

TEST_F(BrokenVolume, ZeroAreaFace) {
  // Find a grid edge a-b whose float midpoint is exactly on it, then split the face (a, b, c)
  // into (a, m, c), (m, b, c) and the sliver (b, m, a), which closes the mesh again.
  for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
    const auto [a, b, c] = mesh.triangle(t);
    const auto pa = mesh.vertex(a), pb = mesh.vertex(b);
    const std::array<float, 3> pm = {(pa[0] + pb[0]) / 2, (pa[1] + pb[1]) / 2, (pa[2] + pb[2]) / 2};
    double u[3], w[3];
    for (int k = 0; k < 3; ++k) u[k] = double(pb[k]) - pa[k], w[k] = double(pm[k]) - pa[k];
    if (u[1] * w[2] - u[2] * w[1] != 0 || u[2] * w[0] - u[0] * w[2] != 0 ||
        u[0] * w[1] - u[1] * w[0] != 0)
      continue;
    const std::uint32_t m = add_vertex(mesh, pm);
    set_triangle(mesh, t, a, m, c);
    mesh.indices.insert(mesh.indices.end(), {m, b, c, b, m, a});
    expect_rejected(kCheckDegenerate);
    const CheckResult* d = with_light.find(kCheckDegenerate);
    EXPECT_EQ(d->count, 1u);
    ASSERT_EQ(d->offenders.size(), 1u);
    EXPECT_EQ(d->offenders[0].faces,
              std::vector<std::int64_t>{std::int64_t(mesh.num_triangles() - 1)});
    for (std::string_view name : {kCheckClosed, kCheckManifold, kCheckOriented, kCheckOutward})
      EXPECT_EQ(status_of(with_light, name), CheckStatus::passed) << name;
    return;
  }
  FAIL() << "no edge with an exactly representable midpoint";
}

TEST_F(BrokenVolume, CollapsedFace) {
  // A face naming one vertex twice: degenerate (and its edges no longer pair up).
  mesh.indices[3 * 5 + 2] = mesh.indices[3 * 5];
  expect_rejected(kCheckDegenerate);
}

TEST_F(BrokenVolume, EdgeSharedByThreeFaces) {
  const auto [a, b, c] = mesh.triangle(10);
  const auto pc = mesh.vertex(c);
  const std::uint32_t x = add_vertex(mesh, {pc[0] + 0.5f, pc[1], pc[2] + 0.5f});
  mesh.indices.insert(mesh.indices.end(), {b, a, x});
  expect_rejected(kCheckManifold);
  const CheckResult* e = with_light.find(kCheckManifold);
  EXPECT_EQ(e->count, 1u);
  ASSERT_EQ(e->offenders.size(), 1u);
  EXPECT_EQ(e->offenders[0].faces.size(), 3u);
  EXPECT_EQ(std::min(e->offenders[0].vertices[0], e->offenders[0].vertices[1]), std::min(a, b));
  EXPECT_EQ(std::max(e->offenders[0].vertices[0], e->offenders[0].vertices[1]), std::max(a, b));
}

TEST_F(BrokenVolume, IndexOutOfRange) {
  mesh.indices[7] = static_cast<std::uint32_t>(mesh.num_vertices() + 3);
  expect_rejected(kCheckIndices);
  EXPECT_EQ(status_of(with_light, kCheckClosed), CheckStatus::skipped);
}

TEST_F(BrokenVolume, LightAwayFromTheApex) {
  // The volume checked against a light above its apex, outside it: the fan faces the light and
  // the solid angles add up to 0, not to the cone.
  light.position = {0, 5, 0};
  const CheckReport r = check_volume(mesh, &light);
  EXPECT_FALSE(r.valid());
  EXPECT_EQ(status_of(r, kCheckNesting), CheckStatus::failed);
  EXPECT_NEAR(r.light_sum, 0, 1e-9);
  EXPECT_NEAR(r.light_expected, 4 * std::numbers::pi, 1e-12);
  // Below the apex, inside: the volume is star-shaped from there too, and the sum is 4π.
  light.position = {0, 3.5, 0};
  const CheckReport inside = check_volume(mesh, &light);
  EXPECT_TRUE(inside.valid()) << inside.first_failure();
  EXPECT_NEAR(inside.light_sum, 4 * std::numbers::pi, 1e-9);
}

TEST_F(BrokenVolume, ApexWithinTheQuantizationStepOfTheLight) {
  // A quantized file's apex lies up to half a step off the light: 5·10⁻⁵ below it here (the
  // light above the apex, outside the volume), but within a 10⁻⁴ step of it.
  light.position = {0, 4 + 5e-5, 0};
  EXPECT_FALSE(check_volume_linear(mesh, &light).valid());
  const CheckReport r = check_volume_linear(mesh, &light, 5, 1e-4);
  EXPECT_TRUE(r.valid()) << r.first_failure();
  EXPECT_EQ(r.quantization_step, 1e-4);
  EXPECT_NE(r.find(kCheckNesting)->detail.find("the light at vertex"), std::string::npos);
  EXPECT_NE(
      r.find(kCheckNesting)->detail.find("from it, within the positions' quantization step 0.0001"),
      std::string::npos)
      << r.find(kCheckNesting)->detail;
  // Beyond the step it is a light outside the volume again.
  light.position = {0, 4 + 5e-4, 0};
  EXPECT_FALSE(check_volume_linear(mesh, &light, 5, 1e-4).valid());
}

// Long faces (the fan) go through an AABB tree instead of CGAL's box sweep: both routes must find
// the same intersecting pairs. Ratio 0 sends every face through the tree, a huge ratio none.
TEST_F(BrokenVolume, LongFacesRouteFindsTheSamePairsAsTheSweep) {
  const auto pairs = [](const Mesh& m, double ratio) {
    const detail::CgalChecks c = detail::cgal_checks(m, true, 1000, ratio);
    EXPECT_TRUE(c.built);
    return c.first_pairs;
  };
  EXPECT_TRUE(pairs(mesh, 0).empty());
  EXPECT_TRUE(pairs(mesh, 1e30).empty());
  EXPECT_FALSE(detail::cgal_does_self_intersect(mesh, 0));

  // The apex pushed down through the occluder: fan faces cross grid faces.
  Mesh apex_down = mesh;
  const std::size_t apex = apex_down.num_vertices() - 1;
  apex_down.positions[3 * apex + 1] = 1.0f;  // between the floor (-0.3) and the occluder (2.1)
  const auto tree_pairs = pairs(apex_down, 0), sweep_pairs = pairs(apex_down, 1e30),
             mixed_pairs = pairs(apex_down, 6);  // the fan long, the occluder walls short
  EXPECT_FALSE(sweep_pairs.empty());
  EXPECT_EQ(tree_pairs, sweep_pairs);
  EXPECT_EQ(mixed_pairs, sweep_pairs);
  EXPECT_TRUE(detail::cgal_does_self_intersect(apex_down, 0));

  // The dragged vertex: short faces only.
  const auto p5 = mesh.vertex(grid(5, 3)), p6 = mesh.vertex(grid(6, 4));
  for (int k = 0; k < 3; ++k) mesh.positions[3 * grid(2, 3) + k] = 0.5f * (p5[k] + p6[k]);
  EXPECT_FALSE(pairs(mesh, 1e30).empty());
  EXPECT_EQ(pairs(mesh, 0), pairs(mesh, 1e30));
}

// ---- faces around hubs -------------------------------------------------------------------------

// All pairs both ways: faces around hubs by direction (default), and no hubs (every pair of boxes).
void expect_same_pairs_both_routes(const Mesh& m, bool expect_pairs) {
  const detail::CgalChecks hubs = detail::cgal_checks(m, true, 100000);
  const detail::CgalChecks boxes =
      detail::cgal_checks(m, true, 100000, detail::kLongFaceRatio, std::size_t(-1));
  ASSERT_TRUE(hubs.built && boxes.built);
  EXPECT_EQ(hubs.first_pairs.empty(), !expect_pairs);
  EXPECT_EQ(hubs.first_pairs, boxes.first_pairs);
  EXPECT_EQ(hubs.intersecting_pairs, boxes.intersecting_pairs);
}

// A closed double cone: `n` rim vertices on the unit circle at z = 1, apexes at z = 0 and z = 2.
// Every face shares an apex with half of the others.
Mesh bicone(int n) {
  Mesh m;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * std::numbers::pi * i / n;
    add_vertex(m, {static_cast<float>(std::cos(a)), static_cast<float>(std::sin(a)), 1});
  }
  const std::uint32_t low = add_vertex(m, {0, 0, 0}), high = add_vertex(m, {0, 0, 2});
  for (int i = 0; i < n; ++i) {
    const auto a = static_cast<std::uint32_t>(i), b = static_cast<std::uint32_t>((i + 1) % n);
    m.indices.insert(m.indices.end(), {low, b, a, high, a, b});
  }
  return m;
}

TEST(CgalHubs, SpotApexRouteFindsTheSamePairsAsTheBoxes) {
  // A 40×40 map: the apex has 156 faces, a hub.
  const DepthImage depth = test::make_depth(40, 40, [](int c, int r) {
    return (c >= 10 && c < 20 && r >= 12 && r < 30) ? 0.95f : 0.98f;
  });
  Mesh mesh = *build_static_volume(spot_light(), depth, {}, "test.exr");
  expect_same_pairs_both_routes(mesh, false);
  // The apex pushed down through the occluder: fan faces cross grid faces.
  mesh.positions[3 * (mesh.num_vertices() - 1) + 1] = 1.0f;
  expect_same_pairs_both_routes(mesh, true);
}

TEST(CgalHubs, CrossingFacesAroundOneVertexAreFound) {
  // Rim vertex 0 pulled across the axis and out the other side: its faces cross the faces there
  // around both apexes.
  Mesh folded = bicone(200);
  folded.positions[0] = -1.5f;
  expect_same_pairs_both_routes(folded, true);
  // Rim vertex 0 pushed down onto the plane z = 0.5 but still outside: sound.
  Mesh dented = bicone(200);
  dented.positions[2] = 0.5f;
  expect_same_pairs_both_routes(dented, false);
}

TEST(CgalHubs, FaceThroughTheHubIsFound) {
  // A tetrahedron whose bottom face (z = 2) contains the upper apex in its interior.
  Mesh m = bicone(100);
  const std::uint32_t a = add_vertex(m, {-1, -1, 2}), b = add_vertex(m, {1, -1, 2}),
                      c = add_vertex(m, {0, 1, 2}), d = add_vertex(m, {0, 0, 3});
  m.indices.insert(m.indices.end(), {a, c, b, a, b, d, b, c, d, c, a, d});
  expect_same_pairs_both_routes(m, true);
}

TEST(CgalHubs, AllFacesSharingOneVertexStayFast) {
  // 200,000 faces around one vertex (an open fan, a cone without its base): every box contains
  // the apex, so a box sweep would test 2·10^10 pairs. By direction, their arcs hardly overlap.
  Mesh fan = bicone(200000);
  fan.positions.resize(3 * 200001);  // drop the upper apex
  for (std::size_t t = 0; t < fan.num_triangles(); t += 2)
    for (int k = 0; k < 3; ++k) fan.indices[3 * (t / 2) + k] = fan.indices[3 * t + k];
  fan.indices.resize(3 * 200000);
  const CheckReport report = check_volume(fan, nullptr);
  EXPECT_EQ(status_of(report, kCheckClosed), CheckStatus::failed);  // the rim is a boundary
  EXPECT_EQ(status_of(report, kCheckSelfIntersections), CheckStatus::passed);

  // Two such hubs facing each other (40,000 faces): sound, and closed.
  const CheckReport both = check_volume(bicone(20000), nullptr);
  EXPECT_TRUE(both.valid()) << both.first_failure();
}

TEST(CgalHubs, TwoShellsSharingOneVertexAreNotASurfaceMesh) {
  // Two tetrahedra touching at vertex 0: closed, edge-manifold and oriented, but vertex 0 joins
  // two separate fans, which CGAL's Surface_mesh cannot hold. The CGAL checks say so, naming it.
  Mesh m;
  for (const std::array<float, 3> p : {std::array<float, 3>{0, 0, 0},
                                       {1, 0, 0},
                                       {0, 1, 0},
                                       {0, 0, 1},
                                       {-1, 0, 0},
                                       {0, -1, 0},
                                       {0, 0, -1}})
    add_vertex(m, p);
  m.indices = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3,   // x, y, z ≥ 0
               0, 4, 5, 0, 6, 4, 0, 5, 6, 4, 6, 5};  // x, y, z ≤ 0
  const CheckReport r = check_volume(m, nullptr);
  EXPECT_EQ(status_of(r, kCheckClosed), CheckStatus::passed);
  EXPECT_EQ(status_of(r, kCheckOriented), CheckStatus::passed);
  const CheckResult* si = r.find(kCheckSelfIntersections);
  ASSERT_NE(si, nullptr);
  EXPECT_EQ(si->status, CheckStatus::skipped);
  EXPECT_NE(si->detail.find("at vertex 0, where separate fans of faces meet"), std::string::npos)
      << si->detail;
}

// ---- the edge check's chunks and buckets -------------------------------------------------------

// A closed spot volume of a 300×200 map (about 120,000 faces: 360,000 edge uses, two chunks of
// lower vertices and more), with a 40×30 occluder.
Mesh large_spot_volume() {
  const DepthImage depth = test::make_depth(300, 200, [](int c, int r) {
    return (c >= 100 && c < 140 && r >= 50 && r < 80) ? 0.95f : 0.98f;
  });
  Result<Mesh> mesh = build_static_volume(spot_light(), depth, {}, "test.exr");
  EXPECT_TRUE(mesh.ok());
  return *mesh;
}

// Two reports agree on every count, detail and offender, and on the sums to the last bit.
void expect_same_report(const CheckReport& a, const CheckReport& b) {
  EXPECT_EQ(a.volume, b.volume);
  EXPECT_EQ(a.light_sum, b.light_sum);
  EXPECT_EQ(a.light_expected, b.light_expected);
  ASSERT_EQ(a.checks.size(), b.checks.size());
  for (std::size_t k = 0; k < a.checks.size(); ++k) {
    EXPECT_EQ(a.checks[k].name, b.checks[k].name);
    EXPECT_EQ(a.checks[k].status, b.checks[k].status) << a.checks[k].name;
    EXPECT_EQ(a.checks[k].count, b.checks[k].count) << a.checks[k].name;
    EXPECT_EQ(a.checks[k].detail, b.checks[k].detail) << a.checks[k].name;
    ASSERT_EQ(a.checks[k].offenders.size(), b.checks[k].offenders.size()) << a.checks[k].name;
    for (std::size_t o = 0; o < a.checks[k].offenders.size(); ++o) {
      EXPECT_EQ(a.checks[k].offenders[o].faces, b.checks[k].offenders[o].faces);
      EXPECT_EQ(a.checks[k].offenders[o].vertices, b.checks[k].offenders[o].vertices);
    }
  }
}

TEST(EdgeChunks, LargeVolumeIsSoundAndTheSameOnOneThread) {
  const Mesh mesh = large_spot_volume();
  const Light light = spot_light();
  ASSERT_GT(3 * mesh.num_triangles(), std::size_t{300000});
  const CheckReport all = check_volume_linear(mesh, &light);
  EXPECT_TRUE(all.valid()) << all.first_failure();
  // The volume as signed_volume sums it, to the last bit.
  EXPECT_EQ(all.volume, signed_volume(mesh));
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  expect_same_report(all, check_volume_linear(mesh, &light));
}

TEST(EdgeChunks, DefectsAcrossTheChunksAreAllFoundInOrder) {
  Mesh mesh = large_spot_volume();
  const Light light = spot_light();
  // Flip one face near the start, one in the middle and one near the end: 3 edges each.
  for (const std::size_t t : {std::size_t{7}, mesh.num_triangles() / 2, mesh.num_triangles() - 9})
    std::swap(mesh.indices[3 * t + 1], mesh.indices[3 * t + 2]);
  const CheckReport r = check_volume_linear(mesh, &light, 1000);
  const CheckResult* oriented = r.find(kCheckOriented);
  ASSERT_NE(oriented, nullptr);
  EXPECT_EQ(oriented->count, 9u);
  ASSERT_EQ(oriented->offenders.size(), 9u);
  // In (lower vertex, upper vertex) order, each naming its two faces in face order.
  for (std::size_t o = 0; o < 9; ++o) {
    const Offender& off = oriented->offenders[o];
    ASSERT_EQ(off.faces.size(), 2u);
    EXPECT_LT(off.faces[0], off.faces[1]);
    if (o > 0) {
      const Offender& prev = oriented->offenders[o - 1];
      EXPECT_LT(std::make_pair(prev.vertices[0], prev.vertices[1]),
                std::make_pair(off.vertices[0], off.vertices[1]));
    }
  }
  EXPECT_EQ(status_of(r, kCheckClosed), CheckStatus::passed);
}

TEST(EdgeChunks, FacesInNoOrderGiveTheSameReport) {
  // The faces shuffled: every block of faces reaches every chunk, so the check takes fewer,
  // larger chunks; the verdict and the offenders (renumbered) are the same.
  Mesh mesh = large_spot_volume();
  const Light light = spot_light();
  std::swap(mesh.indices[3 * 500 + 1], mesh.indices[3 * 500 + 2]);
  const std::size_t nt = mesh.num_triangles();
  std::vector<std::size_t> order(nt);
  for (std::size_t t = 0; t < nt; ++t) order[t] = (t * 7919) % nt;  // 7919 is prime to nt
  ASSERT_EQ(std::set<std::size_t>(order.begin(), order.end()).size(), nt);
  Mesh shuffled = mesh;
  std::size_t flipped_at = 0;
  for (std::size_t t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) shuffled.indices[3 * t + k] = mesh.indices[3 * order[t] + k];
    if (order[t] == 500) flipped_at = t;
  }
  const CheckReport a = check_volume_linear(mesh, &light),
                    b = check_volume_linear(shuffled, &light);
  const CheckResult* oa = a.find(kCheckOriented);
  const CheckResult* ob = b.find(kCheckOriented);
  EXPECT_EQ(oa->count, 3u);
  EXPECT_EQ(ob->count, 3u);
  ASSERT_EQ(ob->offenders.size(), 3u);
  for (std::size_t o = 0; o < 3; ++o) {
    EXPECT_EQ(oa->offenders[o].vertices, ob->offenders[o].vertices);
    const auto& faces = ob->offenders[o].faces;
    EXPECT_NE(std::find(faces.begin(), faces.end(), std::int64_t(flipped_at)), faces.end());
  }
}

TEST(LightProof, DistancesPerBlockOfFacesSumToTheSameBitsAsPerFace) {
  // build's faces come in vertex order, so each block of faces computes its vertices' distances
  // from the light once; with the vertices renumbered at random every block names vertices all
  // over the mesh and each face computes its own. Same positions and faces, same face order: the
  // solid angles and the volume must add up to the same bits.
  const Mesh mesh = large_spot_volume();
  const Light light = spot_light();
  const std::size_t nv = mesh.num_vertices();
  ASSERT_GT(nv, std::size_t{2} * 16384);
  std::vector<std::uint32_t> to(nv);
  for (std::size_t v = 0; v < nv; ++v) to[v] = static_cast<std::uint32_t>((v * 7919) % nv);
  ASSERT_EQ(std::set<std::uint32_t>(to.begin(), to.end()).size(), nv);
  Mesh renumbered = mesh;
  for (std::size_t v = 0; v < nv; ++v)
    for (int k = 0; k < 3; ++k) renumbered.positions[3 * to[v] + k] = mesh.positions[3 * v + k];
  for (std::uint32_t& i : renumbered.indices) i = to[i];
  const CheckReport a = check_volume_linear(mesh, &light),
                    b = check_volume_linear(renumbered, &light);
  EXPECT_TRUE(a.valid()) << a.first_failure();
  EXPECT_TRUE(b.valid()) << b.first_failure();
  EXPECT_EQ(a.light_sum, b.light_sum);
  EXPECT_EQ(a.volume, b.volume);
  EXPECT_NEAR(a.light_expected, b.light_expected, 1e-12);
}

// The variants of the large spot volume that the face pass's two ways must agree on: sound, and
// broken so that faces leave the vectorized lanes for classify_from_point in each of its ways.
std::vector<std::pair<std::string, Mesh>> face_pass_variants() {
  const Mesh sound = large_spot_volume();
  std::vector<std::pair<std::string, Mesh>> out;
  out.emplace_back("sound", sound);
  const std::size_t mid = sound.num_triangles() / 2;
  const auto add = [&](std::string name, const auto& change) {
    Mesh m = sound;
    change(m);
    out.emplace_back(std::move(name), std::move(m));
  };
  add("faces flipped", [&](Mesh& m) {
    for (const std::size_t t : {std::size_t{7}, mid, mid + 1, m.num_triangles() - 9})
      std::swap(m.indices[3 * t + 1], m.indices[3 * t + 2]);
  });
  add("a vertex pulled towards the light", [&](Mesh& m) {
    const std::uint32_t v = m.indices[3 * mid];
    for (int k = 0; k < 3; ++k) m.positions[3 * v + k] *= 0.3f;
  });
  const float eye[3] = {0, 4, 0};  // spot_light()'s position
  add("a vertex close to the light (large angles)", [&](Mesh& m) {
    const std::uint32_t v = m.indices[3 * mid + 1];
    for (int k = 0; k < 3; ++k) m.positions[3 * v + k] = eye[k] + 1e-3f * (k == 1 ? -1.0f : 0.5f);
  });
  add("edge-on faces (a vertex on its neighbour's ray)", [&](Mesh& m) {
    const std::uint32_t v = m.indices[3 * mid], w = m.indices[3 * mid + 1];
    for (int k = 0; k < 3; ++k)
      m.positions[3 * v + k] = eye[k] + 0.9f * (m.positions[3 * w + k] - eye[k]);
  });
  add("degenerate faces (a repeated vertex, zero area)", [&](Mesh& m) {
    m.indices[3 * 100 + 1] = m.indices[3 * 100];
    const std::uint32_t a = m.indices[3 * mid], b = m.indices[3 * mid + 1],
                        c = m.indices[3 * mid + 2];
    for (int k = 0; k < 3; ++k)
      m.positions[3 * c + k] =
          m.positions[3 * a + k] + 2 * (m.positions[3 * b + k] - m.positions[3 * a + k]);
  });
  add("a NaN coordinate", [&](Mesh& m) {
    m.positions[3 * m.indices[3 * mid] + 1] = std::numeric_limits<float>::quiet_NaN();
  });
  add("an infinite and a huge coordinate", [&](Mesh& m) {
    m.positions[3 * m.indices[3 * mid]] = std::numeric_limits<float>::infinity();
    m.positions[3 * m.indices[3 * (mid + 4000)] + 2] = 1e30f;
  });
  return out;
}

TEST(LightProof, FacesDecidedInLanesSumToTheSameBitsAsOneByOne) {
  // The face pass decides most faces from a point light in vectorized lanes (when a block's faces
  // name a narrow range of vertices, as build writes them) and sends the others to
  // classify_from_point; with LightView::lanes false every face goes there. On the sound volume
  // and on each break, the two must give the same sums to the bit, the same counts and the same
  // faces around the apex, and each break must show in them.
  const Light light = spot_light();
  for (const auto& [name, mesh] : face_pass_variants()) {
    SCOPED_TRACE(name);
    const detail::VertexScan scan = detail::scan_vertices(mesh, &light, 0);
    ASSERT_EQ(scan.at_light.size(), 1u);
    detail::LightView lanes = detail::point_view(mesh, light, scan, 0);
    detail::LightView one_by_one = lanes;
    one_by_one.lanes = false;
    const detail::FaceSums a = detail::face_pass(mesh, lanes);
    const detail::FaceSums b = detail::face_pass(mesh, one_by_one);
    const auto same_bits = [](double x, double y) { return std::memcmp(&x, &y, sizeof x) == 0; };
    EXPECT_TRUE(same_bits(a.det, b.det)) << a.det << " " << b.det;
    EXPECT_EQ(a.degenerate, b.degenerate);
    EXPECT_TRUE(same_bits(a.light.positive, b.light.positive))
        << a.light.positive << " " << b.light.positive;
    EXPECT_TRUE(same_bits(a.light.negative, b.light.negative));
    EXPECT_TRUE(same_bits(a.light.zeroed, b.light.zeroed));
    EXPECT_TRUE(same_bits(a.light.source, b.light.source));
    EXPECT_EQ(a.light.wrong, b.light.wrong);
    EXPECT_EQ(a.apex_link, b.apex_link);
    if (name == "sound") {
      EXPECT_EQ(a.light.wrong, 0u);
      EXPECT_EQ(a.degenerate, 0u);
      EXPECT_GT(a.apex_link.size(), 0u);
    }
    if (name == "faces flipped") {
      EXPECT_GE(a.light.wrong, 3u);  // the fourth is a face of the apex's fan: left out
    }
    if (name == "a vertex pulled towards the light") {
      EXPECT_GT(a.light.wrong, 0u);
    }
    if (name.rfind("degenerate", 0) == 0) {
      EXPECT_GE(a.degenerate, 2u);
    }
    if (name.rfind("edge-on", 0) == 0) {
      EXPECT_GT(a.light.zeroed + double(a.light.wrong), 0.0);
    }
    if (name == "a NaN coordinate") {
      EXPECT_TRUE(std::isnan(a.det));
    }
  }
  // The whole check, lanes and all, rejects each break (the edge-on faces count zero and leave a
  // sound volume), with the same report on one thread as on two.
  for (const auto& [name, mesh] : face_pass_variants()) {
    SCOPED_TRACE(name);
    const CheckReport all = check_volume_linear(mesh, &light);
    EXPECT_EQ(all.valid(), name == "sound" || name.rfind("edge-on", 0) == 0) << all.first_failure();
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    const CheckReport serial = check_volume_linear(mesh, &light);
    if (std::isnan(all.volume))
      EXPECT_EQ(all.first_failure(), serial.first_failure());
    else
      expect_same_report(all, serial);
  }
}

TEST_F(BrokenVolume, DuplicatedFace) {
  // A face listed twice: its three edges are used three times (by it twice and its neighbour).
  const auto [a, b, c] = mesh.triangle(12);
  mesh.indices.insert(mesh.indices.end(), {a, b, c});
  expect_rejected(kCheckManifold);
  const CheckResult* m = with_light.find(kCheckManifold);
  EXPECT_EQ(m->count, 3u);
  for (const Offender& o : m->offenders) {
    ASSERT_EQ(o.faces.size(), 3u);
    EXPECT_EQ(o.faces[0] == 12 || o.faces[1] == 12, true);
    EXPECT_EQ(o.faces[2], std::int64_t(mesh.num_triangles() - 1));
  }
}

TEST_F(BrokenVolume, EdgeSharedByFourFaces) {
  // A second sheet through edge a-b with both directions (x→... a-b-x and b-a-y): each direction
  // used twice, so pairing uses one way each is not enough.
  const auto [a, b, c] = mesh.triangle(10);
  const auto pc = mesh.vertex(c);
  const std::uint32_t x = add_vertex(mesh, {pc[0] + 0.5f, pc[1], pc[2] + 0.5f});
  const std::uint32_t y = add_vertex(mesh, {pc[0] - 0.5f, pc[1], pc[2] - 0.5f});
  mesh.indices.insert(mesh.indices.end(), {a, b, x, b, a, y});
  expect_rejected(kCheckManifold);
  const CheckResult* e = with_light.find(kCheckManifold);
  ASSERT_EQ(e->offenders.size(), e->count);
  bool found = false;
  for (const Offender& o : e->offenders)
    if (std::min(o.vertices[0], o.vertices[1]) == std::min(a, b) &&
        std::max(o.vertices[0], o.vertices[1]) == std::max(a, b)) {
      found = true;
      EXPECT_EQ(o.faces.size(), 4u);
    }
  EXPECT_TRUE(found);
}

TEST(EdgeChunks, VertexOfAHundredThousandFacesAndUnreferencedVertices) {
  // A closed double cone whose apexes have 100,000 faces each, with unused vertices before and
  // after: closed, manifold, oriented, outward, no T-junctions.
  Mesh m;
  for (const float k : {0.f, 1.f, 2.f}) add_vertex(m, {5 + k, 5, 5});
  const Mesh cone = bicone(100000);
  const auto offset = static_cast<std::uint32_t>(m.num_vertices());
  m.positions.insert(m.positions.end(), cone.positions.begin(), cone.positions.end());
  for (const std::uint32_t i : cone.indices) m.indices.push_back(i + offset);
  add_vertex(m, {-5, -5, -5});
  const CheckReport r = check_volume_linear(m, nullptr);
  for (std::string_view name : {kCheckIndices, kCheckClosed, kCheckManifold, kCheckOriented,
                                kCheckOutward, kCheckDegenerate, kCheckTJunctions})
    EXPECT_EQ(status_of(r, name), CheckStatus::passed) << name;
  // An omni light inside it proves it too.
  Light inside = test::light_from_json(
      R"({"type": "omni", "position": [0, 0, 1], "near": 0.1, "far": 30, "depth": "radial"})");
  const CheckReport lit = check_volume_linear(m, &inside);
  EXPECT_TRUE(lit.valid()) << lit.first_failure();
  EXPECT_NEAR(lit.light_sum, 4 * std::numbers::pi, 1e-6);

  // One rim face flipped: its edges to the hub are found among the hub's 200,000 uses.
  std::swap(m.indices[3 * 77 + 1], m.indices[3 * 77 + 2]);
  const CheckReport bad = check_volume_linear(m, nullptr);
  EXPECT_EQ(status_of(bad, kCheckOriented), CheckStatus::failed);
  EXPECT_EQ(bad.find(kCheckOriented)->count, 3u);
}

// ---- check_closed_outward: the same linear checks as one answer -----------------------------

TEST(ClosedOutward, SoundVolumePassesAndEachBreakIsNamed) {
  const Mesh sound = sound_spot_volume();
  EXPECT_TRUE(check_closed_outward(sound, "v").ok());

  Mesh open = sound;
  open.indices.resize(open.indices.size() - 3);
  Status s = check_closed_outward(open, "open.drc");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().message.rfind("open.drc: closed: ", 0), 0u) << s.error().message;

  Mesh inverted = sound;
  for (std::size_t t = 0; t < inverted.num_triangles(); ++t)
    std::swap(inverted.indices[3 * t + 1], inverted.indices[3 * t + 2]);
  s = check_closed_outward(inverted, "in.drc");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().message.rfind("in.drc: outward: signed volume -", 0), 0u)
      << s.error().message;

  Mesh flipped = sound;
  std::swap(flipped.indices[4], flipped.indices[5]);
  s = check_closed_outward(flipped, "f.drc");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().message.rfind("f.drc: oriented: ", 0), 0u) << s.error().message;

  EXPECT_FALSE(check_closed_outward(Mesh{}, "empty").ok());
}

}  // namespace
}  // namespace lightvol
