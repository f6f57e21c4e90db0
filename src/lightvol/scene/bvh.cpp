#include <algorithm>
#include <cmath>
#include <limits>

#include <lightvol/core/check.h>
#include <lightvol/scene/bvh.h>

namespace lightvol {

Bvh::Bvh(const Mesh& mesh) : mesh_(mesh) {
  const std::size_t n = mesh.num_triangles();
  LV_CHECK(n < std::numeric_limits<std::uint32_t>::max());
  order_.resize(n);
  std::vector<float> centroids(3 * n);
  for (std::size_t t = 0; t < n; ++t) {
    order_[t] = static_cast<std::uint32_t>(t);
    for (int c = 0; c < 3; ++c) {
      float s = 0;
      for (int k = 0; k < 3; ++k) s += mesh.positions[3 * mesh.indices[3 * t + k] + c];
      centroids[3 * t + c] = s / 3.0f;
    }
  }
  nodes_.reserve(n > 0 ? 2 * n / 2 + 1 : 1);
  if (n > 0) build(0, static_cast<std::uint32_t>(n), centroids);
}

std::uint32_t Bvh::build(std::uint32_t begin, std::uint32_t end, std::vector<float>& centroids) {
  const auto index = static_cast<std::uint32_t>(nodes_.size());
  nodes_.push_back({});
  Node node{};
  float clo[3], chi[3];
  for (int c = 0; c < 3; ++c) {
    node.lo[c] = clo[c] = std::numeric_limits<float>::max();
    node.hi[c] = chi[c] = std::numeric_limits<float>::lowest();
  }
  for (std::uint32_t i = begin; i < end; ++i) {
    const std::uint32_t t = order_[i];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = mesh_.indices[3 * t + k];
      for (int c = 0; c < 3; ++c) {
        node.lo[c] = std::min(node.lo[c], mesh_.positions[3 * v + c]);
        node.hi[c] = std::max(node.hi[c], mesh_.positions[3 * v + c]);
      }
    }
    for (int c = 0; c < 3; ++c) {
      clo[c] = std::min(clo[c], centroids[3 * t + c]);
      chi[c] = std::max(chi[c], centroids[3 * t + c]);
    }
  }
  if (end - begin <= 4) {
    node.first = begin;
    node.count = end - begin;
    nodes_[index] = node;
    return index;
  }
  int axis = 0;
  for (int c = 1; c < 3; ++c)
    if (chi[c] - clo[c] > chi[axis] - clo[axis]) axis = c;
  const std::uint32_t mid = begin + (end - begin) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                   [&](std::uint32_t a, std::uint32_t b) {
                     return centroids[3 * a + axis] < centroids[3 * b + axis];
                   });
  node.count = 0;
  nodes_[index] = node;
  build(begin, mid, centroids);
  const std::uint32_t right = build(mid, end, centroids);
  nodes_[index].first = right;
  return index;
}

void Bvh::intersect_all(Vec3d origin, Vec3d direction, double t_min,
                        std::vector<RayHit>* hits) const {
  if (nodes_.empty()) return;
  const double inv[3] = {1.0 / direction.x, 1.0 / direction.y, 1.0 / direction.z};
  const double o[3] = {origin.x, origin.y, origin.z};
  std::uint32_t stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    // Slab test, slightly widened so that rays along a box face are not lost to rounding.
    double t0 = t_min, t1 = std::numeric_limits<double>::infinity();
    bool miss = false;
    for (int c = 0; c < 3 && !miss; ++c) {
      const double pad = 1e-6 * (1.0 + std::abs(node.lo[c]) + std::abs(node.hi[c]));
      double a = (node.lo[c] - pad - o[c]) * inv[c];
      double b = (node.hi[c] + pad - o[c]) * inv[c];
      if (std::isnan(a) || std::isnan(b)) continue;  // parallel ray exactly on a slab plane
      if (a > b) std::swap(a, b);
      t0 = std::max(t0, a);
      t1 = std::min(t1, b);
      miss = t0 > t1;
    }
    if (miss) continue;
    if (node.count == 0) {
      LV_CHECK_LT(top + 2, 64);
      stack[top++] = node.first;
      stack[top++] = static_cast<std::uint32_t>(&node - nodes_.data()) + 1;
      continue;
    }
    for (std::uint32_t i = node.first; i < node.first + node.count; ++i) {
      const std::uint32_t tri = order_[i];
      const auto v = mesh_.triangle(tri);
      const auto pa = mesh_.vertex(v[0]), pb = mesh_.vertex(v[1]), pc = mesh_.vertex(v[2]);
      const Vec3d a{pa[0], pa[1], pa[2]}, b{pb[0], pb[1], pb[2]}, c{pc[0], pc[1], pc[2]};
      const Vec3d e1 = b - a, e2 = c - a;
      const Vec3d p = cross(direction, e2);
      const double det = dot(e1, p);
      const Vec3d normal = cross(e1, e2);
      if (det == 0 || dot(normal, normal) == 0) continue;
      const double inv_det = 1.0 / det;
      const Vec3d s = origin - a;
      // Edges are widened by kEdge (barycentric): Möller–Trumbore rounds u and w differently in
      // the two triangles of a shared edge, and a ray through the edge could miss both, losing a
      // crossing (a volume entered and never left: the reference was 13x off at such pixels).
      // Widened, it hits both at the same t; dedupe_hits counts that once.
      constexpr double kEdge = 1e-9;
      const double u = dot(s, p) * inv_det;
      if (u < -kEdge || u > 1 + kEdge) continue;
      const Vec3d q = cross(s, e1);
      const double w = dot(direction, q) * inv_det;
      if (w < -kEdge || u + w > 1 + kEdge) continue;
      const double t = dot(e2, q) * inv_det;
      if (t <= t_min) continue;
      hits->push_back({t, dot(normal, direction), tri});
    }
  }
}

void dedupe_hits(std::vector<RayHit>* hits) {
  std::sort(hits->begin(), hits->end(), [](const RayHit& a, const RayHit& b) { return a.t < b.t; });
  std::vector<RayHit> kept;
  kept.reserve(hits->size());
  for (const RayHit& h : *hits) {
    bool repeat = false;
    for (auto it = kept.rbegin(); it != kept.rend(); ++it) {
      if (h.t - it->t > 1e-9 * std::max(1.0, h.t)) break;
      if ((it->facing > 0) == (h.facing > 0)) {
        repeat = true;
        break;
      }
    }
    if (!repeat) kept.push_back(h);
  }
  hits->swap(kept);
}

}  // namespace lightvol
