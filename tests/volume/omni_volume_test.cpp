// The static omni volume: counts, the cube's adjacency against the texel-ray geometry, closedness
// edge by edge, every triangle facing away from the light (solid angles adding up to 4π), and the
// exact volume of a cube room seen from its centre.
#include <algorithm>
#include <cmath>
#include <functional>
#include <set>
#include <string>
#include <tuple>

#include <gtest/gtest.h>

#include <lightvol/depth/cube_faces.h>
#include <lightvol/volume/build_volume.h>
#include <lightvol/volume/omni_adaptive.h>
#include <lightvol/volume/omni_volume.h>
#include <lightvol/volume/static_volume.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

using test::constant_depth;
using test::has_no_degenerate_triangles;
using test::is_closed_and_oriented;
using test::light_from_json;
using test::make_depth;

constexpr double kPi = 3.14159265358979323846;

std::string omni_json(const std::string& depth = "linear", bool flip_y = false,
                      const std::string& position = "[1, 2, 3]") {
  return R"({"type": "omni", "position": )" + position + R"(, "near": 0.1, "far": 20, "depth": ")" +
         depth + "\", \"flip_y\": " + (flip_y ? "true" : "false") + "}";
}

CubeFaces cube_of(const std::function<DepthImage(int face)>& make) {
  CubeFaces cube;
  for (int f = 0; f < kOmniFaces; ++f) {
    cube.faces[f] = make(f);
    cube.sources[f] = "face" + std::to_string(f);
  }
  return cube;
}

// Depths that vary on every face, with some texels at the far plane (nothing hit).
CubeFaces bumpy_cube(int w) {
  return cube_of([w](int f) {
    return make_depth(w, w, [f](int c, int r) {
      if ((c * 7 + r * 3 + f) % 11 == 0) return 25.0f;  // beyond far = 20
      return static_cast<float>(2.0 + 1.5 * std::sin(0.7 * c + 0.3 * f) * std::cos(0.4 * r));
    });
  });
}

Mesh build(const Light& light, const CubeFaces& cube, Space space = Space::world) {
  VolumeOptions options;
  options.space = space;
  Result<Mesh> mesh = build_omni_volume(light, cube, options);
  EXPECT_TRUE(mesh.ok()) << (mesh ? "" : mesh.error().message);
  return mesh ? std::move(*mesh) : Mesh{};
}

Vec3d point(const Mesh& mesh, std::uint32_t v, Vec3d origin) {
  const auto p = mesh.vertex(v);
  return Vec3d{p[0], p[1], p[2]} - origin;
}

// Signed solid angle of triangle (a, b, c) seen from the origin (Van Oosterom & Strackee).
double solid_angle(Vec3d a, Vec3d b, Vec3d c) {
  const double la = length(a), lb = length(b), lc = length(c);
  const double num = dot(a, cross(b, c));
  const double den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
  return 2 * std::atan2(num, den);
}

// Every triangle faces away from `light` (positive orientation seen from it), and the solid angles
// add up to 4π: every ray from the light leaves the volume exactly once.
::testing::AssertionResult is_star_shaped_from(const Mesh& mesh, Vec3d light) {
  double total = 0;
  for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
    const auto [i, j, k] = mesh.triangle(t);
    const Vec3d a = point(mesh, i, light), b = point(mesh, j, light), c = point(mesh, k, light);
    if (!(dot(a, cross(b, c)) > 0))
      return ::testing::AssertionFailure() << "triangle " << t << " (" << i << ", " << j << ", "
                                           << k << ") does not face away from the light";
    total += solid_angle(a, b, c);
  }
  if (std::abs(total - 4 * kPi) > 1e-9 * static_cast<double>(mesh.num_triangles()) + 1e-9)
    return ::testing::AssertionFailure() << "solid angles add up to " << total << ", not 4 pi";
  return ::testing::AssertionSuccess();
}

// The volume of the static omni volume of a light at the centre of a cube room whose walls are at
// distance d: every face grid lies flat on its wall (a square of half-side d − e, e = d/W the
// texel-centre inset), the seams are flat chamfers and the corners flat triangles, so the volume is
// exactly that of a convex polyhedron, Σ area · (distance from the light) / 3 over its faces.
double chamfered_cube_volume(double d, int w) {
  const double e = d / w;
  const double faces = 6 * 4 * (d - e) * (d - e) * d / 3;  // 6 squares of side 2(d − e) at d
  const double seams = 12 * (2 * (d - e)) * (std::sqrt(2) * e) * ((2 * d - e) / std::sqrt(2)) / 3;
  const double corners = 8 * (std::sqrt(3) / 2 * e * e) * ((3 * d - 2 * e) / std::sqrt(3)) / 3;
  return faces + seams + corners;
}

// The float32 guard runs inside both omni builders, called directly: an omni light 10^6 from the
// origin over a cube a few units across is refused in world space, naming the light and its key,
// and built in light space.
TEST(OmniVolume, BothBuildersRunTheFloat32Guard) {
  const Light far_away = light_from_json(omni_json("linear", false, "[1e6, 10, 0]"));
  const CubeFaces cube = bumpy_cube(16);
  for (const Space space : {Space::world, Space::light}) {
    VolumeOptions options;
    options.space = space;
    options.light_source = "o.json";
    AdaptiveOptions adaptive;
    adaptive.max_error = 0.01;
    const Result<Mesh> results[] = {build_omni_volume(far_away, cube, options),
                                    build_adaptive_omni_volume(far_away, cube, options, adaptive)};
    for (const Result<Mesh>& m : results) {
      if (space == Space::light) {
        EXPECT_TRUE(m.ok()) << m.error().message;
        continue;
      }
      ASSERT_FALSE(m.ok());
      EXPECT_NE(m.error().message.find("o.json: float32 cannot hold this volume"),
                std::string::npos)
          << m.error().message;
      EXPECT_NE(m.error().message.find("key 'position'"), std::string::npos);
    }
  }
}

TEST(OmniVolume, CountsAreExact) {
  const Light light = light_from_json(omni_json());
  for (int w : {2, 3, 8, 33}) {
    const Mesh mesh = build(light, bumpy_cube(w));
    const std::uint64_t w2 = static_cast<std::uint64_t>(w) * w;
    EXPECT_EQ(mesh.num_vertices(), 6 * w2) << "W = " << w;
    EXPECT_EQ(mesh.num_triangles(), 12 * w2 - 4) << "W = " << w;
    const VolumeCounts counts = static_volume_counts(LightType::omni, w, w);
    EXPECT_EQ(counts.vertices, 6 * w2);
    EXPECT_EQ(counts.triangles, 12 * w2 - 4);
  }
}

TEST(OmniVolume, ClosedOutwardAndStarShapedForAnyDepths) {
  for (bool flip_y : {false, true}) {
    const Light light = light_from_json(omni_json("linear", flip_y));
    for (int w : {2, 3, 8, 33}) {
      SCOPED_TRACE("W = " + std::to_string(w) + (flip_y ? ", flip_y" : ""));
      const Mesh mesh = build(light, bumpy_cube(w));
      EXPECT_TRUE(is_closed_and_oriented(mesh));
      EXPECT_TRUE(has_no_degenerate_triangles(mesh));
      EXPECT_TRUE(is_star_shaped_from(mesh, light.position));
      EXPECT_GT(signed_volume(mesh), 0);
    }
  }
}

TEST(OmniVolume, SeamsAndCornersAloneCloseTheFaceGrids) {
  // Remove the seams and corners: exactly the 24 face borders stay open; with them, none.
  const Light light = light_from_json(omni_json());
  const int w = 5;
  Mesh mesh = build(light, bumpy_cube(w));
  ASSERT_TRUE(is_closed_and_oriented(mesh));
  Mesh grids = mesh;
  grids.indices.resize(3 * 6 * 2 * (w - 1) * (w - 1));
  EXPECT_FALSE(is_closed_and_oriented(grids));
  // Each seam strip shares its two long sides with face grids and its end rungs with corners.
  for (int drop = 0; drop < 12; ++drop) {
    Mesh without = mesh;
    const std::size_t begin = 3 * (6 * 2 * (w - 1) * (w - 1) + drop * 2 * (w - 1));
    without.indices.erase(
        without.indices.begin() + static_cast<std::ptrdiff_t>(begin),
        without.indices.begin() + static_cast<std::ptrdiff_t>(begin + 3 * 2 * (w - 1)));
    EXPECT_FALSE(is_closed_and_oriented(without)) << "seam " << drop;
  }
}

TEST(OmniVolume, CubeRoomVolumeIsTheChamferedCube) {
  const double d = 2.5;  // walls at distance d from the light on every side
  for (const std::string encoding : {"linear", "radial", "window"}) {
    const Light light = light_from_json(omni_json(encoding));
    for (int w : {2, 3, 8, 33}) {
      SCOPED_TRACE(encoding + ", W = " + std::to_string(w));
      const CubeFaces cube = cube_of([&](int) {
        return make_depth(w, w, [&](int c, int r) {
          const double x = 2.0 * (c + 0.5) / w - 1, y = 1 - 2.0 * (r + 0.5) / w;
          if (encoding == "radial") return static_cast<float>(d * std::sqrt(1 + x * x + y * y));
          if (encoding == "window") {
            const double n = light.near, f = light.far;
            const double z_ndc = (f + n) / (f - n) - 2 * f * n / ((f - n) * d);
            return static_cast<float>(0.5 * (z_ndc + 1));
          }
          return static_cast<float>(d);
        });
      });
      const Mesh mesh = build(light, cube);
      EXPECT_TRUE(is_closed_and_oriented(mesh));
      EXPECT_NEAR(signed_volume(mesh), chamfered_cube_volume(d, w), 2e-5 * d * d * d);
      // Every vertex lies on a wall of the room.
      for (std::size_t v = 0; v < mesh.num_vertices(); ++v) {
        const Vec3d p = point(mesh, static_cast<std::uint32_t>(v), light.position);
        const double inf_norm = std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)});
        ASSERT_NEAR(inf_norm, d, 2e-5 * d) << "vertex " << v;
      }
    }
  }
}

TEST(OmniVolume, EmptySceneReachesTheFarCube) {
  // Window depth 1 everywhere: nothing hit, every vertex on the far plane of its face.
  const Light light = light_from_json(omni_json("window"));
  const int w = 16;
  const Mesh mesh = build(light, cube_of([&](int) { return constant_depth(w, w, 1.0f); }));
  EXPECT_NEAR(signed_volume(mesh), chamfered_cube_volume(light.far, w),
              2e-5 * std::pow(light.far, 3));
  EXPECT_TRUE(is_star_shaped_from(mesh, light.position));
}

TEST(OmniVolume, LightSpaceIsWorldTranslatedToTheLight) {
  const Light light = light_from_json(omni_json());
  const CubeFaces cube = bumpy_cube(6);
  const Mesh world = build(light, cube, Space::world);
  const Mesh local = build(light, cube, Space::light);
  ASSERT_EQ(world.indices, local.indices);
  ASSERT_EQ(world.positions.size(), local.positions.size());
  for (std::size_t v = 0; v < world.num_vertices(); ++v)
    for (int k = 0; k < 3; ++k)
      ASSERT_NEAR(world.positions[3 * v + k] - light.position[k], local.positions[3 * v + k], 1e-5);
}

TEST(OmniVolume, MismatchedFacesAreErrorsNamingTheFace) {
  const Light light = light_from_json(omni_json());
  CubeFaces cube = bumpy_cube(4);
  cube.faces[3] = constant_depth(5, 5, 2.0f);
  cube.sources[3] = "room_ny.exr";
  Result<Mesh> mesh = build_omni_volume(light, cube, {});
  ASSERT_FALSE(mesh.ok());
  EXPECT_NE(mesh.error().message.find("room_ny.exr: face -Y (ny): is 5x5"), std::string::npos)
      << mesh.error().message;
  cube.faces[3] = constant_depth(4, 3, 2.0f);
  mesh = build_omni_volume(light, cube, {});
  ASSERT_FALSE(mesh.ok());
  EXPECT_NE(mesh.error().message.find("-Y (ny): is 4x3; omni faces must be square"),
            std::string::npos)
      << mesh.error().message;
}

// ---- the face convention and the adjacency, against the geometry of the texel rays -------------

// docs/design.md §2, written out independently of light.cpp: look and up of each face.
const Vec3d kLook[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
const Vec3d kUp[6] = {{0, -1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}, {0, -1, 0}, {0, -1, 0}};

TEST(OmniFaces, TexelRaysFollowTheDesignConvention) {
  for (bool flip_y : {false, true}) {
    const Light light = light_from_json(omni_json("linear", flip_y));
    const int w = 4;
    for (int f = 0; f < kOmniFaces; ++f) {
      const Unprojector u(light, w, w, f, Space::light);
      const Vec3d right = cross(kLook[f], kUp[f]);
      for (int r = 0; r < w; ++r)
        for (int c = 0; c < w; ++c) {
          // Column to the right of the view, first stored row at the top (NDC y = +1).
          const double x = 2.0 * (c + 0.5) / w - 1;
          const double y = (flip_y ? -1 : 1) * (1 - 2.0 * (r + 0.5) / w);
          const Vec3d expected = normalize(kLook[f] + x * right + y * kUp[f]);
          const Vec3d got = normalize(u.near_point(c, r) - u.apex());
          EXPECT_NEAR(length(got - expected), 0, 1e-12)
              << "face " << f << " texel " << c << "," << r;
        }
    }
  }
}

// The ray of texel (col, row) of a face, on the cube |x|∞ = 1.
Vec3d cube_point(const Light& light, int w, int face, int col, int row) {
  const Unprojector u(light, w, w, face, Space::light);
  const Vec3d d = u.near_point(col, row) - u.apex();
  return (1.0 / std::max({std::abs(d.x), std::abs(d.y), std::abs(d.z)})) * d;
}

TEST(OmniFaces, AdjacencyMatchesTheTexelRays) {
  for (bool flip_y : {false, true}) {
    const Light light = light_from_json(omni_json("linear", flip_y));
    const OmniAdjacency adjacency = omni_adjacency(light);
    const int w = 8;
    const double inset = 1 - 1.0 / w;  // border texel centres sit 1/W inside the cube edge
    std::set<std::pair<int, int>> borders_used;
    for (const OmniSeam& seam : adjacency.seams) {
      for (int side = 0; side < 2; ++side)
        EXPECT_TRUE(
            borders_used.insert({seam.face[side], static_cast<int>(seam.border[side])}).second)
            << "border used twice";
      EXPECT_NE(seam.face[0] / 2, seam.face[1] / 2) << "opposite faces never meet";
      // Texel k of one border and its partner straddle the edge: their cube points mirror each
      // other across the edge (equal along it, swapped across it).
      for (int k = 0; k < w; ++k) {
        int ca = 0, ra = 0, cb = 0, rb = 0;
        border_texel(seam.border[0], w, k, &ca, &ra);
        border_texel(seam.border[1], w, seam.reversed ? w - 1 - k : k, &cb, &rb);
        const Vec3d a = cube_point(light, w, seam.face[0], ca, ra);
        const Vec3d b = cube_point(light, w, seam.face[1], cb, rb);
        const Vec3d la = kLook[seam.face[0]], lb = kLook[seam.face[1]];
        EXPECT_NEAR(dot(a, la), 1, 1e-12);
        EXPECT_NEAR(dot(a, lb), inset, 1e-12);
        EXPECT_NEAR(dot(b, lb), 1, 1e-12);
        EXPECT_NEAR(dot(b, la), inset, 1e-12);
        const Vec3d along = cross(la, lb);
        EXPECT_NEAR(dot(a, along), dot(b, along), 1e-12) << "k = " << k;
      }
    }
    EXPECT_EQ(borders_used.size(), 24u);

    std::set<std::tuple<int, bool, bool>> corners_used;
    for (const OmniCorner& corner : adjacency.corners) {
      Vec3d p[3];
      for (int k = 0; k < 3; ++k) {
        EXPECT_TRUE(
            corners_used.insert({corner.face[k], corner.last_col[k], corner.last_row[k]}).second);
        p[k] = cube_point(light, w, corner.face[k], corner.last_col[k] ? w - 1 : 0,
                          corner.last_row[k] ? w - 1 : 0);
      }
      // The three texels surround one cube corner: same octant, each 1/W from it on two axes.
      for (int k = 1; k < 3; ++k)
        for (int a = 0; a < 3; ++a) EXPECT_EQ(p[k][a] > 0, p[0][a] > 0);
      EXPECT_GT(dot(p[0], cross(p[1], p[2])), 0) << "corner triangle faces the light";
    }
    EXPECT_EQ(corners_used.size(), 24u);
  }
}

// docs/design.md §2: a depth before the near plane is put on the near plane. Radial depths of 0,
// 1e-20 and 1e-39 (a float denormal) on every face, at corners, borders and inside, build the
// same volume as a depth of half the near distance, static (it aborted on an internal check) and
// adaptive with either tessellation (it refused the pixel as unreachable); static vertices there
// are the texels' near-plane points.
TEST(OmniVolume, RadialDepthsAtZeroAreOnTheNearPlaneInEveryBuild) {
  const Light light = light_from_json(omni_json("radial"));
  const int w = 9;
  const auto tiny = [w](int f, int c, int r) {
    return (c == 0 && r == 0) || (c == w - 1 && r == w - 1) || (c == 4 && r == f) ||
           (r == w - 1 && c == (f + 2) % w);
  };
  const auto cube_with = [&](float value) {
    const CubeFaces bumps = bumpy_cube(w);
    return cube_of([&](int f) {
      return make_depth(
          w, w, [&](int c, int r) { return tiny(f, c, r) ? value : bumps.faces[f].at(c, r); });
    });
  };
  std::vector<BuildVolumeOptions> builds(3);
  builds[1].grid = builds[2].grid = VolumeGrid::adaptive;
  builds[1].adaptive.max_error = builds[2].adaptive.max_error = 0.01;
  builds[2].adaptive.tessellation = Tessellation::quadtree;
  std::vector<Mesh> expected;
  for (const BuildVolumeOptions& options : builds) {
    Result<Mesh> mesh = build_volume(light, ShadowMaps::faces(cube_with(0.05f)), options);
    ASSERT_TRUE(mesh.ok()) << mesh.error().message;
    expected.push_back(std::move(*mesh));
  }
  for (const float value : {0.0f, 1e-20f, 1e-39f}) {
    for (std::size_t b = 0; b < builds.size(); ++b) {
      SCOPED_TRACE("depth " + std::to_string(value) + ", build " + std::to_string(b));
      Result<Mesh> mesh = build_volume(light, ShadowMaps::faces(cube_with(value)), builds[b]);
      ASSERT_TRUE(mesh.ok()) << mesh.error().message;
      EXPECT_EQ(mesh->positions, expected[b].positions);
      EXPECT_EQ(mesh->indices, expected[b].indices);
      EXPECT_TRUE(is_closed_and_oriented(*mesh));
      EXPECT_TRUE(is_star_shaped_from(*mesh, light.position));
    }
    const Mesh mesh = build(light, cube_with(value));
    for (int f = 0; f < kOmniFaces; ++f) {
      const Unprojector u(light, w, w, f, Space::world);
      for (int r = 0; r < w; ++r)
        for (int c = 0; c < w; ++c) {
          if (!tiny(f, c, r)) continue;
          const Vec3d n = u.near_point(c, r);
          EXPECT_EQ(mesh.vertex(static_cast<std::size_t>((f * w + r) * w + c)),
                    (std::array<float, 3>{static_cast<float>(n.x), static_cast<float>(n.y),
                                          static_cast<float>(n.z)}))
              << "face " << f << " texel (" << c << ", " << r << ")";
        }
    }
  }
}

}  // namespace
}  // namespace lightvol
