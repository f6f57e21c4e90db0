// The static light volume of an omni light (docs/design.md §2, §3): six cube-face grids, the twelve
// cube edges joined by seam strips, the eight cube corners closed by one triangle each.
//
// For six W×W faces: 6W² vertices (face f's texel (col, row) is vertex f·W² + row·W + col; no
// vertex at the light) and 12W² − 4 triangles, in this order: the six face grids (2(W−1)² each,
// face by face, as build_static_volume triangulates a grid), the twelve seams (2(W−1) each, in
// omni_adjacency() order), the eight corners. Every triangle faces away from the light: the
// volume is closed, outward and star-shaped from the light position (its triangles' solid angles,
// seen from the light, add up to 4π), whatever the depths.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>
#include <lightvol/depth/cube_faces.h>
#include <lightvol/light/light.h>
#include <lightvol/volume/static_volume.h>

namespace lightvol {

// A border of a W×W face: its texels in order k = 0..W−1.
enum class FaceBorder {
  top,     // row 0, col k
  bottom,  // row W−1, col k
  left,    // col 0, row k
  right,   // col W−1, row k
};

// The texel (col, row) at position k along `border` of a W×W face.
inline void border_texel(FaceBorder border, int width, int k, int* col, int* row) {
  switch (border) {
    case FaceBorder::top:
      *col = k, *row = 0;
      return;
    case FaceBorder::bottom:
      *col = k, *row = width - 1;
      return;
    case FaceBorder::left:
      *col = 0, *row = k;
      return;
    case FaceBorder::right:
      *col = width - 1, *row = k;
      return;
  }
}

// One cube edge: border[0] of face[0] faces border[1] of face[1]. Texel k of the first border
// meets texel k (reversed: W−1−k) of the second. With A_k, B_k those texels, the seam strip is
// the triangles (A_k, A_k+1, B_k) and (A_k+1, B_k+1, B_k), k = 0..W−2, wound the other way when
// `flip` (so that they face away from the light).
struct OmniSeam {
  std::array<int, 2> face{};
  std::array<FaceBorder, 2> border{};
  bool reversed = false;
  bool flip = false;
};

// One cube corner: the corner texels of three faces (corner_col/row: false → 0, true → W−1),
// listed so that the triangle of their vertices faces away from the light.
struct OmniCorner {
  std::array<int, 3> face{};
  std::array<bool, 3> last_col{};
  std::array<bool, 3> last_row{};
};

struct OmniAdjacency {
  std::array<OmniSeam, 12> seams;
  std::array<OmniCorner, 8> corners;
};

// The cube's adjacency for `light`'s face frames (omni_face_view, and flip_y), derived from the
// geometry of the texel rays: which border meets which, in which direction, and the winding that
// faces away from the light. Independent of W. `light` must be an omni light.
OmniAdjacency omni_adjacency(const Light& light);

// Builds the static omni volume from six validated equal square faces (validate_cube_faces; an
// Error otherwise, naming the face). Depths are stored values of the light's encoding; errors name
// cube.sources. A volume float32 cannot hold is refused with check_representable's Error
// (volume/float32_guard.h), naming options.light_source.
Result<Mesh> build_omni_volume(const Light& light, const CubeFaces& cube,
                               const VolumeOptions& options);

// The triangles of build_omni_volume's volume of six W×W faces of `light`, in its order: they
// depend on W and the light's face frames only, never on the depths (for the GPU's live volume).
std::vector<std::uint32_t> omni_volume_indices(const Light& light, int width);

}  // namespace lightvol
