#include <numbers>

#include <lightvol/core/math.h>

namespace lightvol {
// Cofactor expansion (as in MESA's gluInvertMatrix), in double precision.
Mat4d inverse(const Mat4d& a, bool* ok) {
  const auto& m = a.m;
  Mat4d r;
  auto& inv = r.m;
  inv[0] = m[5] * m[10] * m[15] - m[5] * m[11] * m[14] - m[9] * m[6] * m[15] + m[9] * m[7] * m[14] +
           m[13] * m[6] * m[11] - m[13] * m[7] * m[10];
  inv[4] = -m[4] * m[10] * m[15] + m[4] * m[11] * m[14] + m[8] * m[6] * m[15] -
           m[8] * m[7] * m[14] - m[12] * m[6] * m[11] + m[12] * m[7] * m[10];
  inv[8] = m[4] * m[9] * m[15] - m[4] * m[11] * m[13] - m[8] * m[5] * m[15] + m[8] * m[7] * m[13] +
           m[12] * m[5] * m[11] - m[12] * m[7] * m[9];
  inv[12] = -m[4] * m[9] * m[14] + m[4] * m[10] * m[13] + m[8] * m[5] * m[14] -
            m[8] * m[6] * m[13] - m[12] * m[5] * m[10] + m[12] * m[6] * m[9];
  inv[1] = -m[1] * m[10] * m[15] + m[1] * m[11] * m[14] + m[9] * m[2] * m[15] -
           m[9] * m[3] * m[14] - m[13] * m[2] * m[11] + m[13] * m[3] * m[10];
  inv[5] = m[0] * m[10] * m[15] - m[0] * m[11] * m[14] - m[8] * m[2] * m[15] + m[8] * m[3] * m[14] +
           m[12] * m[2] * m[11] - m[12] * m[3] * m[10];
  inv[9] = -m[0] * m[9] * m[15] + m[0] * m[11] * m[13] + m[8] * m[1] * m[15] - m[8] * m[3] * m[13] -
           m[12] * m[1] * m[11] + m[12] * m[3] * m[9];
  inv[13] = m[0] * m[9] * m[14] - m[0] * m[10] * m[13] - m[8] * m[1] * m[14] + m[8] * m[2] * m[13] +
            m[12] * m[1] * m[10] - m[12] * m[2] * m[9];
  inv[2] = m[1] * m[6] * m[15] - m[1] * m[7] * m[14] - m[5] * m[2] * m[15] + m[5] * m[3] * m[14] +
           m[13] * m[2] * m[7] - m[13] * m[3] * m[6];
  inv[6] = -m[0] * m[6] * m[15] + m[0] * m[7] * m[14] + m[4] * m[2] * m[15] - m[4] * m[3] * m[14] -
           m[12] * m[2] * m[7] + m[12] * m[3] * m[6];
  inv[10] = m[0] * m[5] * m[15] - m[0] * m[7] * m[13] - m[4] * m[1] * m[15] + m[4] * m[3] * m[13] +
            m[12] * m[1] * m[7] - m[12] * m[3] * m[5];
  inv[14] = -m[0] * m[5] * m[14] + m[0] * m[6] * m[13] + m[4] * m[1] * m[14] - m[4] * m[2] * m[13] -
            m[12] * m[1] * m[6] + m[12] * m[2] * m[5];
  inv[3] = -m[1] * m[6] * m[11] + m[1] * m[7] * m[10] + m[5] * m[2] * m[11] - m[5] * m[3] * m[10] -
           m[9] * m[2] * m[7] + m[9] * m[3] * m[6];
  inv[7] = m[0] * m[6] * m[11] - m[0] * m[7] * m[10] - m[4] * m[2] * m[11] + m[4] * m[3] * m[10] +
           m[8] * m[2] * m[7] - m[8] * m[3] * m[6];
  inv[11] = -m[0] * m[5] * m[11] + m[0] * m[7] * m[9] + m[4] * m[1] * m[11] - m[4] * m[3] * m[9] -
            m[8] * m[1] * m[7] + m[8] * m[3] * m[5];
  inv[15] = m[0] * m[5] * m[10] - m[0] * m[6] * m[9] - m[4] * m[1] * m[10] + m[4] * m[2] * m[9] +
            m[8] * m[1] * m[6] - m[8] * m[2] * m[5];
  const double det = m[0] * inv[0] + m[1] * inv[4] + m[2] * inv[8] + m[3] * inv[12];
  const bool invertible = std::isfinite(det) && det != 0.0;
  if (ok) *ok = invertible;
  if (invertible)
    for (double& x : inv) x /= det;
  return r;
}

double determinant(const Mat4d& a) {
  const auto& m = a.m;
  const double c0 = m[5] * (m[10] * m[15] - m[11] * m[14]) - m[6] * (m[9] * m[15] - m[11] * m[13]) +
                    m[7] * (m[9] * m[14] - m[10] * m[13]);
  const double c1 = m[4] * (m[10] * m[15] - m[11] * m[14]) - m[6] * (m[8] * m[15] - m[11] * m[12]) +
                    m[7] * (m[8] * m[14] - m[10] * m[12]);
  const double c2 = m[4] * (m[9] * m[15] - m[11] * m[13]) - m[5] * (m[8] * m[15] - m[11] * m[12]) +
                    m[7] * (m[8] * m[13] - m[9] * m[12]);
  const double c3 = m[4] * (m[9] * m[14] - m[10] * m[13]) - m[5] * (m[8] * m[14] - m[10] * m[12]) +
                    m[6] * (m[8] * m[13] - m[9] * m[12]);
  return m[0] * c0 - m[1] * c1 + m[2] * c2 - m[3] * c3;
}

Mat4d look_at(Vec3d eye, Vec3d direction, Vec3d up) {
  const Vec3d f = normalize(direction);
  const Vec3d s = normalize(cross(f, up));
  const Vec3d u = cross(s, f);
  Mat4d r;
  r.m = {s.x,  s.y,  s.z,  -dot(s, eye),  //
         u.x,  u.y,  u.z,  -dot(u, eye),  //
         -f.x, -f.y, -f.z, dot(f, eye),   //
         0,    0,    0,    1};
  return r;
}

Mat4d perspective(double fov_y_deg, double aspect, double near, double far) {
  const double f = 1.0 / std::tan(fov_y_deg * std::numbers::pi / 360.0);
  Mat4d r;
  r.m = {f / aspect,
         0,
         0,
         0,  //
         0,
         f,
         0,
         0,  //
         0,
         0,
         (far + near) / (near - far),
         2 * far * near / (near - far),  //
         0,
         0,
         -1,
         0};
  return r;
}

Mat4d orthographic(double left, double right, double bottom, double top, double near, double far) {
  Mat4d r;
  r.m = {2 / (right - left),
         0,
         0,
         -(right + left) / (right - left),  //
         0,
         2 / (top - bottom),
         0,
         -(top + bottom) / (top - bottom),  //
         0,
         0,
         -2 / (far - near),
         -(far + near) / (far - near),  //
         0,
         0,
         0,
         1};
  return r;
}

}  // namespace lightvol
