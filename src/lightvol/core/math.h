// Small fixed-size linear algebra in double precision: just what the light model needs.
// Matrices are row-major and act on column vectors (OpenGL conventions: p' = M · p).
#pragma once

#include <array>
#include <cmath>

namespace lightvol {

struct Vec3d {
  double x = 0, y = 0, z = 0;

  friend Vec3d operator+(Vec3d a, Vec3d b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
  friend Vec3d operator-(Vec3d a, Vec3d b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
  friend Vec3d operator*(double s, Vec3d a) { return {s * a.x, s * a.y, s * a.z}; }
  friend Vec3d operator*(Vec3d a, double s) { return s * a; }
  double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
};

inline double dot(Vec3d a, Vec3d b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3d cross(Vec3d a, Vec3d b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double length(Vec3d a) { return std::sqrt(dot(a, a)); }
inline Vec3d normalize(Vec3d a) { return (1.0 / length(a)) * a; }

struct Mat4d {
  std::array<double, 16> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};  // row-major

  double operator()(int row, int col) const { return m[4 * row + col]; }
  double& operator()(int row, int col) { return m[4 * row + col]; }

  static Mat4d identity() { return {}; }
  friend Mat4d operator*(const Mat4d& a, const Mat4d& b) {
    Mat4d r;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        double s = 0;
        for (int k = 0; k < 4; ++k) s += a(i, k) * b(k, j);
        r(i, j) = s;
      }
    return r;
  }
  // Transforms the point (p, 1) and divides by w.
  Vec3d transform_point(Vec3d p) const {
    const double x = m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3];
    const double y = m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7];
    const double z = m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11];
    const double w = m[12] * p.x + m[13] * p.y + m[14] * p.z + m[15];
    return {x / w, y / w, z / w};
  }
  // Transforms the direction (d, 0), ignoring the projective row.
  Vec3d transform_vector(Vec3d d) const {
    return {m[0] * d.x + m[1] * d.y + m[2] * d.z, m[4] * d.x + m[5] * d.y + m[6] * d.z,
            m[8] * d.x + m[9] * d.y + m[10] * d.z};
  }
};

// Inverse of a 4×4 matrix; `ok` is false (and the result unspecified) when it is singular.
Mat4d inverse(const Mat4d& a, bool* ok = nullptr);
double determinant(const Mat4d& a);

// OpenGL's gluLookAt / gluPerspective / glOrtho, as row-major matrices.
Mat4d look_at(Vec3d eye, Vec3d direction, Vec3d up);
Mat4d perspective(double fov_y_deg, double aspect, double near, double far);
Mat4d orthographic(double left, double right, double bottom, double top, double near, double far);

}  // namespace lightvol
