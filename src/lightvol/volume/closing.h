// Closing a grid surface into a volume (docs/design.md §3): the spot fan to the light position, or
// the directional walls down to the near plane and the cap there. Shared by the static and the
// adaptive volumes, so both close exactly the border vertices their grids use.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <lightvol/core/mesh.h>
#include <lightvol/light/light.h>

namespace lightvol {

// One vertex of the grid's border ring: its index in the mesh and its texel.
struct BorderVertex {
  std::uint32_t index = 0;
  int col = 0;
  int row = 0;
};

// The border vertices of a W×H grid as a ring, given which texels of each side are vertices.
// `sides` holds ascending positions along top (row 0: columns), right (column W−1: rows),
// bottom (row H−1: columns) and left (column 0: rows); each side lists both of its corners.
// `index(col, row)` is the mesh index of a border texel. The ring runs the way the grid's boundary
// edges do under `standard` winding (top row left to right, right column down, bottom row right
// to left, left column up), reversed otherwise (Unprojector::standard_winding()).
template <class IndexOf>
std::vector<BorderVertex> border_ring(int width, int height, const std::vector<int> (&sides)[4],
                                      bool standard, IndexOf index) {
  std::vector<BorderVertex> ring;
  const auto add = [&](int col, int row) { ring.push_back({index(col, row), col, row}); };
  for (std::size_t k = 0; k + 1 < sides[0].size(); ++k) add(sides[0][k], 0);
  for (std::size_t k = 0; k + 1 < sides[1].size(); ++k) add(width - 1, sides[1][k]);
  for (std::size_t k = sides[2].size() - 1; k > 0; --k) add(sides[2][k], height - 1);
  for (std::size_t k = sides[3].size() - 1; k > 0; --k) add(0, sides[3][k]);
  if (!standard) std::reverse(ring.begin(), ring.end());
  return ring;
}

// Vertices and triangles the closing adds for a ring of `ring_size` border vertices:
// spot 1 and ring_size; directional ring_size + 1 and 3·ring_size.
struct ClosingCounts {
  std::uint64_t vertices = 0;
  std::uint64_t triangles = 0;
};
ClosingCounts closing_counts(LightType type, std::size_t ring_size);

// The closing's own vertices (float xyz, numbered from `first_vertex` on) and its triangles, as
// append_closing adds them: for a producer that does not hold the grid (StaticVolumeStream).
struct ClosingPart {
  std::vector<float> positions;
  std::vector<std::uint32_t> indices;
};
ClosingPart make_closing(LightType type, const Unprojector& unproject, int width, int height,
                         const std::vector<BorderVertex>& ring, std::uint32_t first_vertex);

// Appends the closing to `mesh`, whose grid vertices (positions in `unproject`'s frame) and grid
// triangles are already there. spot: the apex vertex, then one triangle (next, cur, apex) per ring
// edge. directional: a near-plane copy of each ring vertex (in ring order) and the cap's centre,
// then per ring edge two wall triangles and one cap triangle. The ring comes from border_ring.
void append_closing(LightType type, const Unprojector& unproject, int width, int height,
                    const std::vector<BorderVertex>& ring, Mesh* mesh);

}  // namespace lightvol
