#include <algorithm>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <lightvol/core/mesh.h>

namespace lightvol {

Bounds bounding_box(const Mesh& mesh) {
  Bounds b;
  const std::size_t n = mesh.num_vertices();
  if (n == 0) return b;
  for (int k = 0; k < 3; ++k) b.min[k] = b.max[k] = mesh.positions[k];
  for (std::size_t v = 0; v < n; ++v) {
    for (int k = 0; k < 3; ++k) {
      const double x = mesh.positions[3 * v + k];
      b.min[k] = std::min(b.min[k], x);
      b.max[k] = std::max(b.max[k], x);
    }
  }
  return b;
}

double signed_volume(const Mesh& mesh) {
  const float* p = mesh.positions.data();
  const std::uint32_t* idx = mesh.indices.data();
  return tbb::parallel_deterministic_reduce(
             tbb::blocked_range<std::size_t>(0, mesh.num_triangles(), 1 << 16), 0.0,
             [&](const tbb::blocked_range<std::size_t>& r, double acc) {
               for (std::size_t t = r.begin(); t != r.end(); ++t) {
                 const float* a = p + 3 * idx[3 * t];
                 const float* b = p + 3 * idx[3 * t + 1];
                 const float* c = p + 3 * idx[3 * t + 2];
                 const double ax = a[0], ay = a[1], az = a[2];
                 const double bx = b[0], by = b[1], bz = b[2];
                 const double cx = c[0], cy = c[1], cz = c[2];
                 acc +=
                     ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx);
               }
               return acc;
             },
             [](double x, double y) { return x + y; }) /
         6.0;
}

}  // namespace lightvol
