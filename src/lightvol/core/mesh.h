// The core mesh: flat buffers of positions and triangle indices.
//
// A multi-million-triangle light volume must build in seconds and fit in memory, so the mesh is
// two arrays, nothing more. Convert to OpenMesh, Draco or CGAL types only where their algorithms
// are needed, at the edge of the pipeline.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace lightvol {

struct Mesh {
  std::vector<float> positions;        // x0 y0 z0 x1 y1 z1 ...; the frame is the producer's to say
  std::vector<std::uint32_t> indices;  // three per triangle, counter-clockwise seen from outside

  std::size_t num_vertices() const { return positions.size() / 3; }
  std::size_t num_triangles() const { return indices.size() / 3; }
  std::array<float, 3> vertex(std::size_t v) const {
    return {positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]};
  }
  std::array<std::uint32_t, 3> triangle(std::size_t t) const {
    return {indices[3 * t], indices[3 * t + 1], indices[3 * t + 2]};
  }
};

struct Bounds {
  std::array<double, 3> min{0, 0, 0};
  std::array<double, 3> max{0, 0, 0};
};

// Axis-aligned bounding box of the vertices (all zeros for an empty mesh).
Bounds bounding_box(const Mesh& mesh);

// Signed enclosed volume, Σ det(a, b, c) / 6 over the triangles, in double precision. Positive for
// a closed mesh oriented outward; meaningless for an open one.
double signed_volume(const Mesh& mesh);

// det(a, b, c) in double precision: six times the signed volume of the tetrahedron (origin, a, b,
// c), the term signed_volume sums for triangle (a, b, c).
inline double volume_det(const float* a, const float* b, const float* c) {
  const double ax = a[0], ay = a[1], az = a[2];
  const double bx = b[0], by = b[1], bz = b[2];
  const double cx = c[0], cy = c[1], cz = c[2];
  return ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx);
}

// signed_volume sums its terms as tbb::parallel_deterministic_reduce over blocked_range(0, n,
// kSignedVolumeGrain) does; a sum that must equal it to the bit (SignedVolumeSum, the check's face
// pass) splits the triangles the same way.
inline constexpr std::size_t kSignedVolumeGrain = std::size_t{1} << 16;

// Welds vertices with bit-identical positions (STL files, Draco decodes): returns the mesh with
// each position once, in order of first use, and the triangles re-indexed. O(n log n) on any input;
// linear when no two positions are identical (a hash table finds none), and then the mesh is
// returned as it is.
Mesh weld_identical_positions(Mesh mesh);

}  // namespace lightvol
