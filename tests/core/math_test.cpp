#include <gtest/gtest.h>

#include <lightvol/core/math.h>

namespace lightvol {
namespace {

void expect_matrix_near(const Mat4d& a, const Mat4d& b, double tol) {
  for (int i = 0; i < 16; ++i) EXPECT_NEAR(a.m[i], b.m[i], tol) << "element " << i;
}

TEST(Math, InverseOfProjectionTimesItselfIsIdentity) {
  const Mat4d p = perspective(60, 1.5, 0.1, 30) * look_at({1, 2, 3}, {0, -1, 0.2}, {0, 0, -1});
  bool ok = false;
  const Mat4d inv = inverse(p, &ok);
  ASSERT_TRUE(ok);
  expect_matrix_near(p * inv, Mat4d::identity(), 1e-12);
  EXPECT_NEAR(determinant(p) * determinant(inv), 1.0, 1e-12);
}

TEST(Math, SingularMatrixIsReported) {
  Mat4d zero;
  zero.m.fill(0);
  bool ok = true;
  (void)inverse(zero, &ok);
  EXPECT_FALSE(ok);
}

TEST(Math, LookAtMapsEyeToOriginAndDirectionToMinusZ) {
  const Mat4d v = look_at({0, 4, 0}, {0, -1, 0}, {0, 0, -1});
  const Vec3d o = v.transform_point({0, 4, 0});
  EXPECT_NEAR(length(o), 0, 1e-15);
  const Vec3d below = v.transform_point({0, 0, 0});
  EXPECT_NEAR(below.x, 0, 1e-15);
  EXPECT_NEAR(below.y, 0, 1e-15);
  EXPECT_NEAR(below.z, -4, 1e-15);
  // Up (0, 0, −1) is eye +Y.
  const Vec3d up = v.transform_vector({0, 0, -1});
  EXPECT_NEAR(up.y, 1, 1e-15);
}

TEST(Math, PerspectiveMapsNearAndFarToMinusOneAndOne) {
  const Mat4d p = perspective(90, 1, 0.5, 10);
  EXPECT_NEAR(p.transform_point({0, 0, -0.5}).z, -1, 1e-12);
  EXPECT_NEAR(p.transform_point({0, 0, -10}).z, 1, 1e-12);
  // 90° fov: the point (1, 1, -1) lies on the frustum corner.
  const Vec3d corner = p.transform_point({1, 1, -1});
  EXPECT_NEAR(corner.x, 1, 1e-12);
  EXPECT_NEAR(corner.y, 1, 1e-12);
}

TEST(Math, OrthographicMapsExtentsToUnitCube) {
  const Mat4d p = orthographic(-5, 3, -2, 4, 1, 9);
  const Vec3d a = p.transform_point({-5, -2, -1});
  const Vec3d b = p.transform_point({3, 4, -9});
  EXPECT_NEAR(a.x, -1, 1e-12);
  EXPECT_NEAR(a.y, -1, 1e-12);
  EXPECT_NEAR(a.z, -1, 1e-12);
  EXPECT_NEAR(b.x, 1, 1e-12);
  EXPECT_NEAR(b.y, 1, 1e-12);
  EXPECT_NEAR(b.z, 1, 1e-12);
}

}  // namespace
}  // namespace lightvol
