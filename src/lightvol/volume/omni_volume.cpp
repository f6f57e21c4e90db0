#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <lightvol/core/check.h>
#include <lightvol/volume/float32_guard.h>
#include <lightvol/volume/omni_volume.h>

namespace lightvol {
namespace {

constexpr FaceBorder kBorders[4] = {FaceBorder::top, FaceBorder::bottom, FaceBorder::left,
                                    FaceBorder::right};

double det3(Vec3d a, Vec3d b, Vec3d c) { return dot(a, cross(b, c)); }

// The axis (0, 1, 2) of v's largest component among those not excluded, and that component's sign.
int dominant_axis(Vec3d v, int excluded, int* sign) {
  int best = -1;
  for (int a = 0; a < 3; ++a)
    if (a != excluded && (best < 0 || std::abs(v[a]) > std::abs(v[best]))) best = a;
  *sign = v[best] > 0 ? 1 : -1;
  return best;
}

// Texel rays of the six faces of a W×W cube, as directions from the light (world axes).
class CubeRays {
 public:
  CubeRays(const Light& light, int width) : width_(width) {
    for (int f = 0; f < kOmniFaces; ++f) faces_.emplace_back(light, width, width, f, Space::light);
    for (int f = 0; f < kOmniFaces; ++f) {
      const int w = width - 1;
      const Vec3d centre = dir(f, 0, 0) + dir(f, w, 0) + dir(f, 0, w) + dir(f, w, w);
      axis_[f] = dominant_axis(centre, -1, &sign_[f]);
    }
  }
  int width() const { return width_; }
  Vec3d dir(int face, int col, int row) const {
    return faces_[face].near_point(col, row) - faces_[face].apex();
  }
  Vec3d dir(int face, FaceBorder border, int k) const {
    int col = 0, row = 0;
    border_texel(border, width_, k, &col, &row);
    return dir(face, col, row);
  }
  // The ray's point on the cube |x|∞ = 1 (on face `face`'s plane).
  Vec3d cube_point(int face, FaceBorder border, int k) const {
    const Vec3d d = dir(face, border, k);
    return (1.0 / std::abs(d[axis_[face]])) * d;
  }
  int axis(int face) const { return axis_[face]; }
  int sign(int face) const { return sign_[face]; }

 private:
  int width_;
  std::vector<Unprojector> faces_;
  std::array<int, kOmniFaces> axis_{}, sign_{};
};

void put(std::vector<float>& positions, std::size_t v, Vec3d p) {
  positions[3 * v] = static_cast<float>(p.x);
  positions[3 * v + 1] = static_cast<float>(p.y);
  positions[3 * v + 2] = static_cast<float>(p.z);
}

}  // namespace

// Long (over 80 lines) on purpose: a table-like derivation of the 12 cube edges' face pairs and
// orientations; splitting it would scatter the table.
OmniAdjacency omni_adjacency(const Light& light) {
  LV_CHECK(light.type == LightType::omni);
  // Two texels per border are enough: the adjacency does not depend on W.
  const CubeRays rays(light, 2);
  const int last = rays.width() - 1;

  // Each face sits on one signed axis; all six must be distinct.
  std::array<std::array<int, 2>, 3> face_on{{{-1, -1}, {-1, -1}, {-1, -1}}};
  for (int f = 0; f < kOmniFaces; ++f) {
    int& slot = face_on[rays.axis(f)][rays.sign(f) > 0];
    LV_CHECK_EQ(slot, -1);
    slot = f;
  }

  // The face across each border: the signed axis its border texels lean towards.
  std::array<std::array<int, 4>, kOmniFaces> across{};
  for (int f = 0; f < kOmniFaces; ++f)
    for (int b = 0; b < 4; ++b) {
      const Vec3d mid =
          0.5 * (rays.cube_point(f, kBorders[b], 0) + rays.cube_point(f, kBorders[b], last));
      int sign = 0;
      const int axis = dominant_axis(mid, rays.axis(f), &sign);
      across[f][b] = face_on[axis][sign > 0];
    }

  OmniAdjacency adjacency;
  int seams = 0;
  for (int f = 0; f < kOmniFaces; ++f)
    for (int b = 0; b < 4; ++b) {
      const int g = across[f][b];
      if (g < f) continue;
      int bg = -1;
      for (int c = 0; c < 4; ++c)
        if (across[g][c] == f) {
          LV_CHECK_EQ(bg, -1);
          bg = c;
        }
      LV_CHECK_LE(0, bg);
      OmniSeam seam;
      seam.face = {f, g};
      seam.border = {kBorders[b], kBorders[bg]};
      // Direction along the cube edge: compare both borders' steps on the edge's axis.
      const int edge_axis = 3 - rays.axis(f) - rays.axis(g);
      const double step_a = rays.cube_point(f, seam.border[0], last)[edge_axis] -
                            rays.cube_point(f, seam.border[0], 0)[edge_axis];
      const double step_b = rays.cube_point(g, seam.border[1], last)[edge_axis] -
                            rays.cube_point(g, seam.border[1], 0)[edge_axis];
      LV_CHECK(step_a != 0 && step_b != 0);
      seam.reversed = (step_a > 0) != (step_b > 0);
      const Vec3d a0 = rays.dir(f, seam.border[0], 0), a1 = rays.dir(f, seam.border[0], 1);
      const Vec3d b0 = rays.dir(g, seam.border[1], seam.reversed ? last : 0);
      const Vec3d b1 = rays.dir(g, seam.border[1], seam.reversed ? last - 1 : 1);
      const double first = det3(a0, a1, b0), second = det3(a1, b1, b0);
      LV_CHECK((first > 0) == (second > 0));
      seam.flip = first < 0;
      LV_CHECK_LT(seams, 12);
      adjacency.seams[seams++] = seam;
    }
  LV_CHECK_EQ(seams, 12);

  // Corners: each face's four corner texels, grouped by the cube corner (octant) they lean to.
  std::array<int, 8> filled{};
  for (int f = 0; f < kOmniFaces; ++f)
    for (int lr = 0; lr < 2; ++lr)
      for (int lc = 0; lc < 2; ++lc) {
        const Vec3d d = rays.dir(f, lc * last, lr * last);
        const int octant = (d.x > 0) | (d.y > 0) << 1 | (d.z > 0) << 2;
        OmniCorner& corner = adjacency.corners[octant];
        const int k = filled[octant]++;
        LV_CHECK_LT(k, 3);
        corner.face[k] = f;
        corner.last_col[k] = lc == 1;
        corner.last_row[k] = lr == 1;
      }
  for (OmniCorner& corner : adjacency.corners) {
    Vec3d d[3];
    for (int k = 0; k < 3; ++k)
      d[k] = rays.dir(corner.face[k], corner.last_col[k] ? last : 0, corner.last_row[k] ? last : 0);
    if (det3(d[0], d[1], d[2]) < 0) {
      std::swap(corner.face[1], corner.face[2]);
      std::swap(corner.last_col[1], corner.last_col[2]);
      std::swap(corner.last_row[1], corner.last_row[2]);
    }
  }
  for (int n : filled) LV_CHECK_EQ(n, 3);
  return adjacency;
}

namespace {

// The omni volume's triangles into `idx` (12W² − 4 of them): the six face grids, the seams, the
// corners (omni_volume.h's order). `faces` are the six faces' Unprojectors (their windings).
void omni_triangles(const Light& light, const std::vector<Unprojector>& faces, int w,
                    std::uint32_t* idx) {
  const std::size_t face_vertices = static_cast<std::size_t>(w) * static_cast<std::size_t>(w);
  const auto vertex = [&](int face, int col, int row) {
    return static_cast<std::uint32_t>(face * face_vertices + static_cast<std::size_t>(row) * w +
                                      col);
  };
  // Grid triangles: two per texel quad, wound to face away from the light.
  const std::uint32_t uw = static_cast<std::uint32_t>(w);
  const std::size_t quads_per_face = static_cast<std::size_t>(w - 1) * (w - 1);
  tbb::parallel_for(
      tbb::blocked_range<int>(0, kOmniFaces * (w - 1)), [&](const tbb::blocked_range<int>& rows) {
        for (int fr = rows.begin(); fr != rows.end(); ++fr) {
          const int f = fr / (w - 1), r = fr % (w - 1);
          const bool standard = faces[f].standard_winding();
          std::uint32_t* out =
              idx + 6 * (f * quads_per_face + static_cast<std::size_t>(r) * (w - 1));
          for (int c = 0; c + 1 < w; ++c) {
            const std::uint32_t a = vertex(f, c, r), b = a + 1, cc = a + uw, d = cc + 1;
            if (standard) {
              out[0] = a, out[1] = b, out[2] = cc, out[3] = b, out[4] = d, out[5] = cc;
            } else {
              out[0] = a, out[1] = cc, out[2] = b, out[3] = b, out[4] = cc, out[5] = d;
            }
            out += 6;
          }
        }
      });

  // Seams along the twelve cube edges, then one triangle per cube corner.
  const OmniAdjacency adjacency = omni_adjacency(light);
  std::uint32_t* out = idx + 6 * kOmniFaces * quads_per_face;
  const auto emit = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c, bool flip) {
    *out++ = a;
    *out++ = flip ? c : b;
    *out++ = flip ? b : c;
  };
  for (const OmniSeam& seam : adjacency.seams) {
    const auto at = [&](int side, int k) {
      int col = 0, row = 0;
      border_texel(seam.border[side], w, side == 1 && seam.reversed ? w - 1 - k : k, &col, &row);
      return vertex(seam.face[side], col, row);
    };
    for (int k = 0; k + 1 < w; ++k) {
      const std::uint32_t a0 = at(0, k), a1 = at(0, k + 1), b0 = at(1, k), b1 = at(1, k + 1);
      emit(a0, a1, b0, seam.flip);
      emit(a1, b1, b0, seam.flip);
    }
  }
  for (const OmniCorner& corner : adjacency.corners) {
    std::uint32_t v[3];
    for (int k = 0; k < 3; ++k)
      v[k] = vertex(corner.face[k], corner.last_col[k] ? w - 1 : 0, corner.last_row[k] ? w - 1 : 0);
    emit(v[0], v[1], v[2], false);
  }
  LV_CHECK_EQ(static_cast<std::size_t>(out - idx),
              3 * static_volume_counts(LightType::omni, w, w).triangles);
}

}  // namespace

std::vector<std::uint32_t> omni_volume_indices(const Light& light, int width) {
  LV_CHECK(light.type == LightType::omni);
  LV_CHECK(width >= 2);
  std::vector<Unprojector> faces;
  for (int f = 0; f < kOmniFaces; ++f) faces.emplace_back(light, width, width, f, Space::world);
  std::vector<std::uint32_t> indices(3 *
                                     static_volume_counts(LightType::omni, width, width).triangles);
  omni_triangles(light, faces, width, indices.data());
  return indices;
}

Result<Mesh> build_omni_volume(const Light& light, const CubeFaces& cube,
                               const VolumeOptions& options) {
  LV_CHECK(light.type == LightType::omni);
  if (Status s = validate_cube_faces(cube); !s) return s.error();
  const int w = cube.size();
  const VolumeCounts counts = static_volume_counts(LightType::omni, w, w);
  if (counts.vertices >= std::numeric_limits<std::uint32_t>::max())
    return Error{cube.sources[0] + ": faces of " + std::to_string(w) + "x" + std::to_string(w) +
                 " need more vertices than 32-bit indices hold"};

  std::vector<Unprojector> faces;
  for (int f = 0; f < kOmniFaces; ++f) faces.emplace_back(light, w, w, f, options.space);
  const std::size_t face_vertices = static_cast<std::size_t>(w) * static_cast<std::size_t>(w);
  const auto vertex = [&](int face, int col, int row) {
    return static_cast<std::uint32_t>(face * face_vertices + static_cast<std::size_t>(row) * w +
                                      col);
  };

  Mesh mesh;
  mesh.positions.resize(3 * counts.vertices);
  mesh.indices.resize(3 * counts.triangles);

  // Grid vertices: rows of all six faces in parallel.
  tbb::parallel_for(tbb::blocked_range<int>(0, kOmniFaces * w),
                    [&](const tbb::blocked_range<int>& rows) {
                      for (int fr = rows.begin(); fr != rows.end(); ++fr) {
                        const int f = fr / w, r = fr % w;
                        const DepthImage& depth = cube.faces[f];
                        for (int c = 0; c < w; ++c) {
                          Vec3d p;
                          const bool reached = faces[f].point(c, r, depth.at(c, r), &p);
                          LV_CHECK(reached);  // a perspective ray reaches every depth
                          put(mesh.positions, vertex(f, c, r), p);
                        }
                      }
                    });

  // Grid triangles, seams and corners.
  omni_triangles(light, faces, w, mesh.indices.data());
  if (Status s = check_representable(mesh, light, options.space, options.light_source); !s)
    return s.error();
  return mesh;
}

}  // namespace lightvol
