#include <lightvol/core/check.h>
#include <lightvol/volume/closing.h>

namespace lightvol {

ClosingCounts closing_counts(LightType type, std::size_t ring_size) {
  LV_CHECK(type != LightType::omni);
  const std::uint64_t n = ring_size;
  if (type == LightType::spot) return {1, n};
  return {n + 1, 3 * n};
}

ClosingPart make_closing(LightType type, const Unprojector& unproject, int width, int height,
                         const std::vector<BorderVertex>& ring, std::uint32_t first_vertex) {
  LV_CHECK(type != LightType::omni);
  const std::size_t nb = ring.size();
  LV_CHECK(nb >= 3);
  const ClosingCounts add = closing_counts(type, nb);
  ClosingPart part;
  part.positions.reserve(3 * add.vertices);
  part.indices.reserve(3 * add.triangles);
  std::uint32_t next_vertex = first_vertex;
  const auto push_vertex = [&](Vec3d p) {
    part.positions.push_back(static_cast<float>(p.x));
    part.positions.push_back(static_cast<float>(p.y));
    part.positions.push_back(static_cast<float>(p.z));
    return next_vertex++;
  };
  std::vector<std::uint32_t>& out = part.indices;
  if (type == LightType::spot) {
    const std::uint32_t apex = push_vertex(unproject.apex());
    for (std::size_t k = 0; k < nb; ++k) {
      const std::uint32_t cur = ring[k].index, next = ring[(k + 1) % nb].index;
      out.insert(out.end(), {next, cur, apex});
    }
    return part;
  }
  // Near-plane copies of the ring, in ring order, then the cap's centre.
  const std::uint32_t base = next_vertex;
  for (const BorderVertex& b : ring) push_vertex(unproject.near_point(b.col, b.row));
  const Vec3d centre =
      0.25 * (unproject.near_point(0, 0) + unproject.near_point(width - 1, 0) +
              unproject.near_point(0, height - 1) + unproject.near_point(width - 1, height - 1));
  const std::uint32_t cap = push_vertex(centre);
  for (std::size_t k = 0; k < nb; ++k) {
    const std::size_t k1 = (k + 1) % nb;
    const std::uint32_t cur = ring[k].index, next = ring[k1].index;
    const std::uint32_t cur_n = base + static_cast<std::uint32_t>(k);
    const std::uint32_t next_n = base + static_cast<std::uint32_t>(k1);
    out.insert(out.end(), {next, cur, cur_n, next, cur_n, next_n, next_n, cur_n, cap});
  }
  return part;
}

void append_closing(LightType type, const Unprojector& unproject, int width, int height,
                    const std::vector<BorderVertex>& ring, Mesh* mesh) {
  const ClosingPart part = make_closing(type, unproject, width, height, ring,
                                        static_cast<std::uint32_t>(mesh->num_vertices()));
  mesh->positions.insert(mesh->positions.end(), part.positions.begin(), part.positions.end());
  mesh->indices.insert(mesh->indices.end(), part.indices.begin(), part.indices.end());
}

}  // namespace lightvol
