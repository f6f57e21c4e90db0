// Texel → point for every depth encoding, against closed-form points.
//
// The spot light of test::spot_json sits at (0, 4, 0) looking down −Y with up −Z, so its eye
// frame maps to world as x_w = x_e, y_w = 4 + z_e, z_w = −y_e.
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include <lightvol/light/light.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

constexpr double kTan30 = 0.57735026918962576;  // tan(fov/2) for fov 60°

// Closed-form world point of texel (col,row) of a W×H spot map at view-axis distance z.
Vec3d spot_point(int col, int row, int w, int h, double aspect, double z) {
  const double xn = 2.0 * (col + 0.5) / w - 1.0, yn = 1.0 - 2.0 * (row + 0.5) / h;
  const double xe = xn * kTan30 * aspect * z, ye = yn * kTan30 * z;
  return {xe, 4 - z, -ye};
}

void expect_near(Vec3d a, Vec3d b, double tol) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

TEST(Unproject, SpotLinearDepth) {
  const Light l = test::light_from_json(test::spot_json("linear", 1.5));
  const Unprojector u(l, 8, 6, 0, Space::world);
  for (int r : {0, 2, 5})
    for (int c : {0, 3, 7}) {
      Vec3d p;
      ASSERT_TRUE(u.point(c, r, 3.25, &p));
      expect_near(p, spot_point(c, r, 8, 6, 1.5, 3.25), 1e-12);
    }
}

TEST(Unproject, SpotWindowDepth) {
  const Light l = test::light_from_json(test::spot_json("window"));
  const Unprojector u(l, 5, 5, 0, Space::world);
  const double n = 0.1, f = 30, z = 2.5;
  // Window depth of eye distance z: z_ndc = (f+n)/(f−n) − 2fn/((f−n)z), d = (z_ndc + 1)/2.
  const double d = 0.5 * ((f + n) / (f - n) - 2 * f * n / ((f - n) * z) + 1);
  Vec3d p;
  ASSERT_TRUE(u.point(1, 3, d, &p));
  expect_near(p, spot_point(1, 3, 5, 5, 1.0, z), 1e-9);
}

TEST(Unproject, SpotRadialDepth) {
  const Light l = test::light_from_json(test::spot_json("radial"));
  const Unprojector u(l, 7, 7, 0, Space::world);
  const Vec3d dir = spot_point(6, 1, 7, 7, 1.0, 1.0) - Vec3d{0, 4, 0};
  Vec3d p;
  ASSERT_TRUE(u.point(6, 1, 2.0, &p));
  expect_near(p, Vec3d{0, 4, 0} + 2.0 * normalize(dir), 1e-12);
  EXPECT_NEAR(length(p - Vec3d{0, 4, 0}), 2.0, 1e-12);
}

TEST(Unproject, FarAndBeyondGiveTheFarPlaneAndNearClamps) {
  for (const char* enc : {"window", "linear", "radial"}) {
    const Light l = test::light_from_json(test::spot_json(enc));
    const Unprojector u(l, 4, 4, 0, Space::world);
    Vec3d p;
    ASSERT_TRUE(u.point(1, 2, 1e6, &p));
    expect_near(p, spot_point(1, 2, 4, 4, 1.0, 30), 1e-9);
    ASSERT_TRUE(u.point(1, 2, 0.0, &p));
    expect_near(p, spot_point(1, 2, 4, 4, 1.0, 0.1), 1e-9);
    expect_near(u.far_point(1, 2), spot_point(1, 2, 4, 4, 1.0, 30), 1e-9);
    expect_near(u.near_point(1, 2), spot_point(1, 2, 4, 4, 1.0, 0.1), 1e-12);
  }
  const Light w = test::light_from_json(test::spot_json("window"));
  Vec3d p;
  ASSERT_TRUE(Unprojector(w, 4, 4, 0, Space::world).point(0, 0, 1.0, &p));
  expect_near(p, spot_point(0, 0, 4, 4, 1.0, 30), 1e-9);
}

TEST(Unproject, DirectionalEncodings) {
  // ortho [−5, 5, −4, 4], near 0, far 10, at (0, 4, 0) looking down.
  const int w = 10, h = 8;
  const auto expected = [&](int c, int r, double z) {
    const double xe = -5 + 10.0 * (c + 0.5) / w, ye = 4 - 8.0 * (r + 0.5) / h;
    return Vec3d{xe, 4 - z, -ye};
  };
  Vec3d p;
  const Unprojector lin(test::light_from_json(test::directional_json("linear")), w, h, 0,
                        Space::world);
  ASSERT_TRUE(lin.point(3, 5, 6.5, &p));
  expect_near(p, expected(3, 5, 6.5), 1e-12);
  const Unprojector win(test::light_from_json(test::directional_json("window")), w, h, 0,
                        Space::world);
  ASSERT_TRUE(win.point(3, 5, 0.65, &p));  // window depth is linear for ortho
  expect_near(p, expected(3, 5, 6.5), 1e-12);
  const Unprojector rad(test::light_from_json(test::directional_json("radial")), w, h, 0,
                        Space::world);
  const Vec3d lateral = expected(3, 5, 0) - Vec3d{0, 4, 0};
  ASSERT_TRUE(rad.point(3, 5, std::sqrt(dot(lateral, lateral) + 6.5 * 6.5), &p));
  expect_near(p, expected(3, 5, 6.5), 1e-9);
  // A radial depth shorter than the ray's distance from the light cannot be reached.
  EXPECT_FALSE(rad.point(0, 0, 0.5, &p));
}

TEST(Unproject, FlipYMirrorsRowsAndWinding) {
  Light l = test::light_from_json(test::spot_json("linear"));
  const Unprojector plain(l, 4, 4, 0, Space::world);
  l.flip_y = true;
  const Unprojector flipped(l, 4, 4, 0, Space::world);
  Vec3d a, b;
  ASSERT_TRUE(plain.point(1, 0, 2, &a));
  ASSERT_TRUE(flipped.point(1, 3, 2, &b));
  expect_near(a, b, 1e-12);
  EXPECT_TRUE(plain.standard_winding());
  EXPECT_FALSE(flipped.standard_winding());
}

TEST(Unproject, LightSpaceIsTheEyeFrame) {
  const Light l = test::light_from_json(test::spot_json("linear"));
  const Unprojector u(l, 4, 4, 0, Space::light);
  Vec3d p;
  ASSERT_TRUE(u.point(3, 0, 2, &p));
  const Vec3d w = spot_point(3, 0, 4, 4, 1.0, 2);
  expect_near(p, Vec3d{w.x, -w.z, w.y - 4}, 1e-12);
  expect_near(u.apex(), Vec3d{0, 0, 0}, 0);
}

}  // namespace
}  // namespace lightvol
