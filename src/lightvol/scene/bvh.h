// A compact bounding-volume hierarchy over a triangle mesh's flat buffers, for the CPU reference:
// every intersection of a ray with the mesh (not just the nearest).
#pragma once

#include <cstdint>
#include <vector>

#include <lightvol/core/math.h>
#include <lightvol/core/mesh.h>

namespace lightvol {

struct RayHit {
  double t = 0;       // ray parameter (world units along a unit direction)
  double facing = 0;  // dot(triangle normal, ray direction): > 0 leaving (back face), < 0 entering
  std::uint32_t triangle = 0;
};

class Bvh {
 public:
  // Builds over `mesh` (kept by reference: it must outlive the Bvh). Median splits along the
  // longest centroid axis, leaves of at most 4 triangles. O(n log n).
  explicit Bvh(const Mesh& mesh);

  // Appends to `hits` every triangle the ray origin + t·direction crosses with t > t_min, in no
  // particular order; edge-on and degenerate triangles are skipped. Möller–Trumbore in double
  // precision, edges inclusive and widened by 1e-9 in barycentric terms (so that rounding never
  // lets a ray slip between two triangles sharing an edge): a ray through a shared edge or vertex
  // hits several triangles at the same t; `dedupe_hits` removes those repeats.
  void intersect_all(Vec3d origin, Vec3d direction, double t_min, std::vector<RayHit>* hits) const;

  std::size_t num_nodes() const { return nodes_.size(); }

 private:
  struct Node {
    float lo[3], hi[3];
    std::uint32_t first;  // leaf: first index into order_; inner: index of the right child
    std::uint32_t count;  // leaf: number of triangles; inner: 0 (left child is the next node)
  };
  std::uint32_t build(std::uint32_t begin, std::uint32_t end, std::vector<float>& centroids);

  const Mesh& mesh_;
  std::vector<Node> nodes_;
  std::vector<std::uint32_t> order_;
};

// Sorts hits by t and removes repeats: hits within a relative 1e-9 of each other in t and with
// the same sign of facing count once (a ray through a shared edge or vertex of a closed mesh).
void dedupe_hits(std::vector<RayHit>* hits);

}  // namespace lightvol
