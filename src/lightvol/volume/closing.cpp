#include <lightvol/core/check.h>
#include <lightvol/volume/closing.h>

namespace lightvol {

ClosingCounts closing_counts(LightType type, std::size_t ring_size) {
  LV_CHECK(type != LightType::omni);
  const std::uint64_t n = ring_size;
  if (type == LightType::spot) return {1, n};
  return {n + 1, 3 * n};
}

namespace {

std::uint32_t push_vertex(Mesh* mesh, Vec3d p) {
  const std::size_t v = mesh->num_vertices();
  mesh->positions.push_back(static_cast<float>(p.x));
  mesh->positions.push_back(static_cast<float>(p.y));
  mesh->positions.push_back(static_cast<float>(p.z));
  return static_cast<std::uint32_t>(v);
}

}  // namespace

void append_closing(LightType type, const Unprojector& unproject, int width, int height,
                    const std::vector<BorderVertex>& ring, Mesh* mesh) {
  LV_CHECK(type != LightType::omni);
  const std::size_t nb = ring.size();
  LV_CHECK(nb >= 3);
  const ClosingCounts add = closing_counts(type, nb);
  mesh->positions.reserve(mesh->positions.size() + 3 * add.vertices);
  mesh->indices.reserve(mesh->indices.size() + 3 * add.triangles);
  std::vector<std::uint32_t>& out = mesh->indices;
  if (type == LightType::spot) {
    const std::uint32_t apex = push_vertex(mesh, unproject.apex());
    for (std::size_t k = 0; k < nb; ++k) {
      const std::uint32_t cur = ring[k].index, next = ring[(k + 1) % nb].index;
      out.insert(out.end(), {next, cur, apex});
    }
    return;
  }
  // Near-plane copies of the ring, in ring order, then the cap's centre.
  const std::uint32_t base = static_cast<std::uint32_t>(mesh->num_vertices());
  for (const BorderVertex& b : ring) push_vertex(mesh, unproject.near_point(b.col, b.row));
  const Vec3d centre =
      0.25 * (unproject.near_point(0, 0) + unproject.near_point(width - 1, 0) +
              unproject.near_point(0, height - 1) + unproject.near_point(width - 1, height - 1));
  const std::uint32_t cap = push_vertex(mesh, centre);
  for (std::size_t k = 0; k < nb; ++k) {
    const std::size_t k1 = (k + 1) % nb;
    const std::uint32_t cur = ring[k].index, next = ring[k1].index;
    const std::uint32_t cur_n = base + static_cast<std::uint32_t>(k);
    const std::uint32_t next_n = base + static_cast<std::uint32_t>(k1);
    out.insert(out.end(), {next, cur, cur_n, next, cur_n, next_n, next_n, cur_n, cap});
  }
}

}  // namespace lightvol
