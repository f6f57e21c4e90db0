// Coarsening of an adaptive grid by exact-verified half-edge collapses ("collapse" tessellation).
//
// The input is any conforming triangulation of a texel grid whose vertices are texels and which
// meets the bound at every texel (the quadtree of RefinementPyramid::tessellate at the same
// bound). A vertex u is merged into a neighbour v (v stays where it is, so vertices stay texels)
// only when every triangle of u's star that does not hold v keeps its orientation with u replaced
// by v (the new fan then covers exactly the old star: the triangulation stays conforming), and the
// error of every texel under those new triangles, evaluated exactly on their planes in window depth
// (the metric of TexelDepths::error), stays within the bound. Triangles that do not change keep
// their texels' errors, so the bound holds at every texel for the triangles emitted.
//
// Then edges are flipped where the bound allows and the smaller angle grows (flip_sweeps below).
//
// Border vertices move only along their side (a corner never), and not at all on a locked side:
// locked sides keep exactly the border vertices of the input (fixed closures). On an unlocked side,
// the positions listed in `keep` stay too (omni seams: the vertices the neighbouring face keeps).
// In a fixed order (sweeps in texel order over horizontal stripes of 64 rows, the stripes in
// parallel; vertices whose star crosses a stripe's edge then in stripes shifted by 32 rows; those
// that cross both afterwards in order; the flips in triangle order): the same input gives the same
// bytes on any machine and any thread count.
#pragma once

#include <cstdint>
#include <vector>

#include <lightvol/tessellate/adaptive_grid.h>

namespace lightvol {

struct CollapseOptions {
  bool locked[4] = {false, false, false, false};  // per GridSide: keep its border vertices
  // Per GridSide, ascending positions along it (as AdaptiveGrid::border) of border vertices that
  // must stay; positions the input has no vertex at are ignored.
  std::vector<int> keep[4];
  int max_rounds = 64;  // sweeps over the vertices whose star changed in the previous sweep
  // A vertex whose star covers more texels (area in texel units²) is kept: bounds the cost of
  // one attempt (every attempt evaluates the texels of the whole star).
  double max_star_area = 4096;
  // No new triangle narrower than this (texel units) across its longest edge: its height there,
  // twice its area over that edge's length. A lattice triangle has area ≥ 1/2 but can be as thin
  // as 1/L for a longest edge L (nearly collinear corners); after the volume's positions are
  // rounded to float32 such a sliver could turn over. Thin strips along a step (height ≥ 1 texel)
  // stay allowed: they are what make the count small.
  double min_height = 0.25;
  // Sweeps of bound-verified edge flips after the collapses (0: none). An interior edge is flipped
  // when its two triangles form a strictly convex quadrilateral, the other diagonal raises the
  // smaller of their smallest angles (texel space: Delaunay's local criterion), and the texels
  // under both new triangles stay within the bound (and none is thinner than min_height). The
  // count and the vertices stay; only slivers that the bound allows to turn go.
  int flip_sweeps = 8;
  // The flips made the plain way (for tests): every triangle tried in every sweep, every angle
  // comparison on atan2 values. The default skips the tries that cannot succeed and compares the
  // angles exactly first (collapse_grid.cpp); the result is the same.
  bool reference_flips = false;
  // Every texel test made the plain way (for tests): each texel of a new triangle measured. The
  // default first bounds the triangle's error by its corners' depths against the least and
  // greatest depth of aligned blocks covering its bounding box (uniform error scales only), and
  // measures the texels only when that bound exceeds the error bound (collapse_grid.cpp); the
  // result is the same.
  bool reference_texel_tests = false;
  // The schedule as first written (for tests): the even stripes of a sweep, then the odd ones;
  // the collapses of the vertices that cross both kinds of stripe edge one at a time; each flip
  // decided when its turn comes. The default runs all stripes at once, and decides those
  // collapses and flips in parallel ahead of making them in order, deciding again where a step
  // before changed what a decision read (collapse_grid.cpp); the result is the same.
  bool reference_order = false;
};

struct CollapseReport {
  std::uint64_t attempts = 0;   // collapses whose error was evaluated
  std::uint64_t collapses = 0;  // collapses made
  std::uint64_t flips = 0;      // edge flips made
  // The default schedule's bookkeeping (0 with CollapseOptions::reference_order): collapses made
  // in the in-order step (vertices whose star crosses both kinds of stripe edge), and flip tries
  // decided again because a flip before changed a triangle their decision made ahead had read.
  std::uint64_t in_order_collapses = 0;
  std::uint64_t flips_redecided = 0;
  int rounds = 0;
  double seconds = 0;
};

// `grid` must be a conforming triangulation of texels.width() × texels.height() texels meeting
// `bound`. The result keeps its winding (standard or not) and its conventions (vertices in texel
// order, border positions per side).
AdaptiveGrid collapse_grid(const TexelDepths& texels, const AdaptiveGrid& grid, double bound,
                           const CollapseOptions& options = {}, CollapseReport* report = nullptr);
// The same, rewriting the grid's own index buffer instead of a copy of it (no second buffer of the
// grid's size): `grid` is left without indices.
AdaptiveGrid collapse_grid(const TexelDepths& texels, AdaptiveGrid&& grid, double bound,
                           const CollapseOptions& options = {}, CollapseReport* report = nullptr);

// The smallest interior angle (degrees) and the smallest area (texel units²) of a grid's
// triangles, in texel space.
struct GridQuality {
  double min_angle_degrees = 0;
  double min_area = 0;
  double min_height = 0;  // twice the area over the longest edge
};
GridQuality grid_quality(const AdaptiveGrid& grid);

}  // namespace lightvol
