#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <iterator>
#include <limits>
#include <utility>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <lightvol/core/check.h>
#include <lightvol/core/limits.h>
#include <lightvol/tessellate/collapse_grid.h>
#include <lightvol/volume/float32_guard.h>
#include <lightvol/volume/omni_adaptive.h>
#include <lightvol/volume/omni_volume.h>

namespace lightvol {
namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

GridSide grid_side(FaceBorder border) {
  switch (border) {
    case FaceBorder::top:
      return kTop;
    case FaceBorder::bottom:
      return kBottom;
    case FaceBorder::left:
      return kLeft;
    case FaceBorder::right:
      return kRight;
  }
  return kTop;
}

// Border positions of one side, mapped to the other side's numbering (reversed: W−1−p), ascending.
std::vector<int> mapped(const std::vector<int>& positions, bool reversed, int width) {
  std::vector<int> out(positions);
  if (reversed) {
    for (int& p : out) p = width - 1 - p;
    std::reverse(out.begin(), out.end());
  }
  return out;
}

std::vector<int> merged(const std::vector<int>& a, const std::vector<int>& b) {
  std::vector<int> out;
  out.reserve(a.size() + b.size());
  std::set_union(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
  return out;
}

// Each seam's border vertices: the union of its two faces' (in each face's numbering). For each
// face side that lacks some of them, calls require(face, side, union) and marks the face dirty;
// returns whether any did.
template <typename Require>
bool unite_seams(const OmniAdjacency& adjacency, const std::array<AdaptiveGrid, kOmniFaces>& grids,
                 int width, std::array<bool, kOmniFaces>* dirty, Require require) {
  bool changed = false;
  for (const OmniSeam& seam : adjacency.seams) {
    const GridSide sa = grid_side(seam.border[0]), sb = grid_side(seam.border[1]);
    const std::vector<int>& a = grids[seam.face[0]].border[sa];
    const std::vector<int>& b = grids[seam.face[1]].border[sb];
    std::vector<int> both = merged(a, mapped(b, seam.reversed, width));
    std::vector<int> both_b = mapped(both, seam.reversed, width);
    if (both != a) {
      require(seam.face[0], sa, std::move(both));
      (*dirty)[seam.face[0]] = changed = true;
    }
    if (both_b != b) {
      require(seam.face[1], sb, std::move(both_b));
      (*dirty)[seam.face[1]] = changed = true;
    }
  }
  return changed;
}

}  // namespace

Result<OmniRefinement> OmniRefinement::create(const Light& light, const CubeFaces& cube,
                                              Refinement refinement, Space space, double cap) {
  LV_CHECK(light.type == LightType::omni);
  if (Status s = validate_cube_faces(cube); !s) return s.error();
  const auto start = std::chrono::steady_clock::now();
  OmniRefinement out(light, cube);
  const int w = cube.size();
  out.pyramids_.reserve(kOmniFaces);
  for (int f = 0; f < kOmniFaces; ++f) {
    // The cube outlives this object (see the class): its floats can serve as the depths.
    Result<TexelDepths> texels =
        TexelDepths::create(light, cube.faces[f], f, cube.sources[f], true);
    if (!texels) return texels.error();
    out.pyramids_.emplace_back(std::move(*texels), refinement, cap);
    out.faces_.emplace_back(light, w, w, f, space);
  }
  out.seconds_ = seconds_since(start);
  return out;
}

Result<Mesh> build_adaptive_omni_volume(const Light& light, const CubeFaces& cube,
                                        const VolumeOptions& volume, const AdaptiveOptions& options,
                                        AdaptiveReport* report, OmniAdaptiveDetail* detail) {
  const Result<double> bound = adaptive_bound(options);
  if (!bound) return bound.error();
  Result<OmniRefinement> refinement =
      OmniRefinement::create(light, cube, options.refinement, volume.space, *bound);
  if (!refinement) return refinement.error();
  Status memory;
  Mesh mesh =
      refinement->build(*bound, options.measure, report, detail, options.tessellation, &memory);
  if (!memory) return memory.error();
  if (Status s = check_representable(mesh, light, volume.space, volume.light_source); !s)
    return s.error();
  return mesh;
}

// Long (over 80 lines) on purpose: the six faces' tessellation rounds (seam vertices forced across
// faces until no face adds any) and the assembly share the per-face state; split, it would pass
// that state around without making a step readable on its own.
Mesh OmniRefinement::build(double bound, bool measure, AdaptiveReport* report,
                           OmniAdaptiveDetail* detail, Tessellation tessellation,
                           Status* memory) const {
  const CubeFaces& cube = *cube_;
  const std::vector<RefinementPyramid>& pyramids = pyramids_;
  const std::vector<Unprojector>& faces = faces_;
  const int w = cube.size();
  AdaptiveReport r;
  OmniAdaptiveDetail d;
  r.pyramid_seconds = seconds_;

  const bool collapse =
      pyramids[0].refinement() == Refinement::max_error && tessellation == Tessellation::collapse;
  const bool floats = std::all_of(pyramids.begin(), pyramids.end(), [](const RefinementPyramid& p) {
    return p.texels().float_depths();
  });
  // What grows with the tessellation (the quadtree's triangles, the collapse's tables, the volume)
  // is measured against the budget: as each face's leaves are counted, with the other faces'
  // grids as they stand (before its triangles are emitted), and once the seams agree. A refusal
  // gives the estimate for all six faces: the faces the round has not reached yet are counted
  // (their leaves, nothing emitted), so that raising the budget to it is not refused again at the
  // next face.
  const auto within_budget = [&](std::uint64_t triangles) {
    *memory = check_memory(adaptive_memory_bytes(w, w, kOmniFaces, triangles, collapse, floats),
                           cube.sources[0], "the adaptive omni volume at this bound");
    return memory->ok();
  };

  // Tessellate; force each border to hold its neighbour's border vertices until they agree.
  const OmniAdjacency adjacency = omni_adjacency(light_);
  std::array<BorderSplits, kOmniFaces> forced;
  std::array<AdaptiveGrid, kOmniFaces> grids;
  std::array<bool, kOmniFaces> dirty;
  dirty.fill(true);
  for (;;) {
    ++d.seam_rounds;
    LV_CHECK_LE(d.seam_rounds, 4 * w + 4);  // every round adds at least one border vertex
    for (int f = 0; f < kOmniFaces; ++f) {
      if (!dirty[f]) continue;
      // The other faces' triangles: their grids as they stand, or (`recount`) for the faces this
      // round has yet to tessellate, their leaves counted afresh, nothing emitted.
      const auto others = [&](bool recount) {
        std::uint64_t n = 0;
        for (int g = 0; g < kOmniFaces; ++g) {
          if (g == f) continue;
          if (recount && g > f && dirty[g])
            n += pyramids[g]
                     .tessellate(bound, faces[g].standard_winding(), forced[g],
                                 [](std::uint64_t) { return false; })
                     .refused_triangles;
          else
            n += grids[g].num_triangles();
        }
        return n;
      };
      const std::uint64_t standing = others(false);
      grids[f] = pyramids[f].tessellate(
          bound, faces[f].standard_winding(), forced[f],
          memory ? std::function<bool(std::uint64_t)>(
                       [&](std::uint64_t triangles) { return within_budget(standing + triangles); })
                 : nullptr);
      if (memory && !*memory) {
        within_budget(grids[f].refused_triangles + others(true));
        return Mesh{};
      }
      dirty[f] = false;
    }
    if (!unite_seams(adjacency, grids, w, &dirty, [&](int f, GridSide side, std::vector<int> p) {
          forced[f].side[side] = std::move(p);
        }))
      break;
  }
  for (const AdaptiveGrid& g : grids) {
    r.balance_seconds += g.balance_seconds;
    r.emit_seconds += g.emit_seconds;
    r.quadtree_triangles += g.num_triangles();
    r.leaves += g.leaves;
    r.fixup_rounds = std::max(r.fixup_rounds, g.fixup_rounds);
  }
  if (memory && !within_budget(r.quadtree_triangles)) return Mesh{};
  if (collapse) {
    // Each face collapses its quadtree grid, seam vertices too (they slide along their side);
    // then each seam keeps what either of its faces kept, and a face that kept less collapses its
    // quadtree grid again keeping those. Keeps only grow (within the quadtree's border), so this
    // ends, with both faces of every seam on the same border vertices.
    const auto collapse_start = std::chrono::steady_clock::now();
    const std::array<AdaptiveGrid, kOmniFaces> quadtree = grids;
    std::array<CollapseOptions, kOmniFaces> keep;
    for (CollapseOptions& k : keep) k.flip_sweeps = 0;  // flips once, after the seams agree
    std::array<CollapseReport, kOmniFaces> reports;
    dirty.fill(true);
    for (;;) {
      ++d.collapse_rounds;
      // Every round after the first keeps another border vertex on some side.
      LV_CHECK_LE(d.collapse_rounds, 4 * kOmniFaces * w + 1);
      tbb::parallel_for(0, kOmniFaces, [&](int f) {
        if (!dirty[f]) return;
        reports[f] = {};
        grids[f] = collapse_grid(pyramids[f].texels(), quadtree[f], bound, keep[f], &reports[f]);
      });
      dirty.fill(false);
      if (!unite_seams(adjacency, grids, w, &dirty, [&](int f, GridSide side, std::vector<int> p) {
            keep[f].keep[side] = std::move(p);
          }))
        break;
    }
    CollapseOptions flips;  // borders locked, no collapses: the flips alone
    for (bool& side : flips.locked) side = true;
    flips.max_rounds = 0;
    tbb::parallel_for(0, kOmniFaces, [&](int f) {
      grids[f] = collapse_grid(pyramids[f].texels(), std::move(grids[f]), bound, flips);
    });
    for (const CollapseReport& c : reports) r.collapses += c.collapses;
    r.collapse_seconds = seconds_since(collapse_start);
  }
  r.min_angle_degrees = 180;
  r.min_area = std::numeric_limits<double>::infinity();
  for (const AdaptiveGrid& g : grids) {
    r.grid_triangles += g.num_triangles();
    const GridQuality quality = grid_quality(g);
    r.min_angle_degrees = std::min(r.min_angle_degrees, quality.min_angle_degrees);
    r.min_area = std::min(r.min_area, quality.min_area);
  }
  if (measure) {
    const auto m = std::chrono::steady_clock::now();
    r.max_error_reached = 0;
    for (int f = 0; f < kOmniFaces; ++f)
      r.max_error_reached = std::max(r.max_error_reached, pyramids[f].measure(grids[f]));
    r.measure_seconds = seconds_since(m);
  }

  // Assemble: each face's vertices (texel order) on their rays, its triangles, then the seams and
  // the corners.
  const auto assemble_start = std::chrono::steady_clock::now();
  std::array<std::uint32_t, kOmniFaces + 1> base{};
  for (int f = 0; f < kOmniFaces; ++f) {
    const std::uint64_t next = std::uint64_t{base[f]} + grids[f].vertices.size();
    LV_CHECK_LT(next,
                std::uint64_t{
                    std::numeric_limits<std::uint32_t>::max()});  // 2^32 vertices: > 16 GB of input
    base[f + 1] = static_cast<std::uint32_t>(next);
  }
  std::uint64_t seam_triangles = 0;
  for (const OmniSeam& seam : adjacency.seams)
    seam_triangles += 2 * (grids[seam.face[0]].border[grid_side(seam.border[0])].size() - 1);
  std::uint64_t triangles = r.grid_triangles + seam_triangles + 8;

  Mesh mesh;
  mesh.positions.resize(3 * std::size_t{base[kOmniFaces]});
  mesh.indices.reserve(3 * triangles);
  const std::uint32_t uw = static_cast<std::uint32_t>(w);
  for (int f = 0; f < kOmniFaces; ++f) {
    const AdaptiveGrid& grid = grids[f];
    const DepthImage& depth = cube.faces[f];
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, grid.vertices.size(), 4096),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        for (std::size_t v = range.begin(); v != range.end(); ++v) {
                          const std::uint32_t id = grid.vertices[v];
                          const int c = static_cast<int>(id % uw), row = static_cast<int>(id / uw);
                          Vec3d p;
                          const bool reached = faces[f].point(c, row, depth.values[id], &p);
                          LV_CHECK(reached);  // a perspective ray reaches every depth
                          float* out = mesh.positions.data() + 3 * (std::size_t{base[f]} + v);
                          out[0] = static_cast<float>(p.x), out[1] = static_cast<float>(p.y),
                          out[2] = static_cast<float>(p.z);
                        }
                      });
    d.face_triangles[f] = grid.num_triangles();
    for (const std::uint32_t i : grid.indices) mesh.indices.push_back(base[f] + i);
  }
  const auto vertex = [&](int face, int col, int row) {
    return base[face] + grids[face].vertex_index(col, row);
  };
  const auto emit = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c, bool flip) {
    mesh.indices.push_back(a);
    mesh.indices.push_back(flip ? c : b);
    mesh.indices.push_back(flip ? b : c);
  };
  for (const OmniSeam& seam : adjacency.seams) {
    const std::vector<int>& along = grids[seam.face[0]].border[grid_side(seam.border[0])];
    LV_CHECK(mapped(along, seam.reversed, w) ==
             grids[seam.face[1]].border[grid_side(seam.border[1])]);
    const auto at = [&](int side, int position) {
      int col = 0, row = 0;
      border_texel(seam.border[side], w, side == 1 && seam.reversed ? w - 1 - position : position,
                   &col, &row);
      return vertex(seam.face[side], col, row);
    };
    for (std::size_t k = 0; k + 1 < along.size(); ++k) {
      const std::uint32_t a0 = at(0, along[k]), a1 = at(0, along[k + 1]);
      const std::uint32_t b0 = at(1, along[k]), b1 = at(1, along[k + 1]);
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
  LV_CHECK_EQ(mesh.num_triangles(), triangles);
  r.assemble_seconds = seconds_since(assemble_start);
  r.vertices = mesh.num_vertices();
  r.triangles = mesh.num_triangles();
  d.seam_triangles = seam_triangles;
  if (report) *report = r;
  if (detail) *detail = d;
  return mesh;
}

}  // namespace lightvol
