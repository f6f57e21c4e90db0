// Adaptive tessellation of one depth image's texel grid (docs/design.md §3 "Adaptive"; the
// paper, Billeter et al. 2010, §4.1).
//
// The grid's vertices are texels (col, row); a quadtree of cells covers the (W−1)×(H−1) quads.
// A cell of level L spans 2^L quads per side, clipped at the far edges of a grid whose size is not
// 2^k + 1, so every cell corner is a texel. A cell is split while its measure exceeds the bound:
//   - max_error: the largest world distance, over the texels the cell covers, between the texel's
//     point and the point of its ray on the cell's triangles, whose window depth is interpolated
//     linearly (a plane of the scene stays a plane in window depth, and a flat triangle of the
//     emitted mesh is exactly such an interpolation along every ray);
//   - laplacian: the paper's edge map, the largest |discrete Laplacian| of window depth over the
//     cell's texels.
// Both measures form a pyramid (each cell: max of its own value and its children's), built once and
// thresholded for any bound. Cells are then 2:1 balanced across edges (restricted quadtree), and
// each leaf emits the one of 16 edge-split configurations (2 to 6 triangles) that uses the
// midpoints of the edges its finer neighbours split: no T-junctions. In max_error mode, a leaf
// whose split configuration breaks the bound is split too, so the bound holds for exactly the
// triangles emitted.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include <lightvol/core/result.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/light/light.h>

namespace lightvol {

// Window depth of every texel of one depth image, and the world distance between points of a
// texel's ray at two window depths. For linear and radial encodings the stored depth is converted
// to the window depth of the light's projection (omni: of face `face`).
class TexelDepths {
 public:
  // Errors name `source` and the pixel: a radial depth that a parallel ray never reaches. With
  // `borrow`, when every stored value is its own window depth (window encoding within [0, 1]; a
  // linear one that converts to itself), the texels read the image's floats in place instead of a
  // copy (a gigabyte of fresh memory at 16384²): `depth` must then outlive this object and its
  // moves.
  static Result<TexelDepths> create(const Light& light, const DepthImage& depth, int face,
                                    const std::string& source, bool borrow = false);

  int width() const { return width_; }
  int height() const { return height_; }
  // The texel's window depth, clamped to [0, 1] (its vertex lies on the far plane at 1).
  double window_depth(int col, int row) const {
    const std::size_t v = index(col, row);
    return float_depths_ ? double{depth_fp_[v]} : depth_[v];
  }
  // World distance between the point of texel (col, row)'s ray at window depth `d` and its own
  // point.
  double error(int col, int row, double d) const {
    const double depth = window_depth(col, row);
    if (uniform_) return std::abs(d - depth) * uniform_scale_;
    return std::abs(d - depth) * scale_[index(col, row)] / std::abs(w0(col, row) + d * w1_);
  }

  // The window depths are held as floats when every one of them is a float exactly (window
  // encoding: the stored value clamped to [0, 1]; linear or radial ones whose conversion happens
  // to round to nothing, as with an orthographic light from 0 to 1): half the memory, and the
  // same doubles once read (a float converts to double exactly), so the same errors, pyramid and
  // grids. The row loops read depth_row_as<float> or depth_row_as<double> accordingly.
  bool float_depths() const { return float_depths_; }
  // The same texels with their depths held as doubles (for tests: the float path against it).
  TexelDepths with_double_depths() const;

  // For the row loops of the tessellator: the error is |d − depth|·scale / |w0 + d·w1| with
  // w0 = w0_c + col·w0_dc + row·w0_dr; with `uniform()`, scale = uniform_scale() and the
  // denominator is 1 everywhere (orthographic projections).
  bool uniform() const { return uniform_; }
  double uniform_scale() const { return uniform_scale_; }
  template <class D>
  const D* depth_row_as(int row) const {
    if constexpr (std::is_same_v<D, float>) {
      return depth_fp_ + index(0, row);
    } else {
      return depth_.get() + index(0, row);
    }
  }
  const double* scale_row(int row) const { return scale_.get() + index(0, row); }
  double w0(int col, int row) const { return w0_c_ + col * w0_dc_ + row * w0_dr_; }
  double w0_dc() const { return w0_dc_; }
  double w1() const { return w1_; }

 private:
  std::size_t index(int col, int row) const {
    return static_cast<std::size_t>(row) * static_cast<std::size_t>(width_) +
           static_cast<std::size_t>(col);
  }
  int width_ = 0, height_ = 0;
  // Per texel, written once in parallel (no serial zero-fill).
  std::unique_ptr<double[]> depth_;   // window depth, or null when float_depths_
  std::unique_ptr<float[]> depth_f_;  // window depth when float_depths_ and not borrowed
  const float* depth_fp_ = nullptr;   // window depth when float_depths_: depth_f_ or the image's
  bool float_depths_ = false;
  std::unique_ptr<double[]> scale_;  // null when uniform
  bool uniform_ = false;
  double uniform_scale_ = 0;
  double w0_c_ = 1, w0_dc_ = 0, w0_dr_ = 0, w1_ = 0;
};

enum class Refinement { max_error, laplacian };

// Sides of a grid: top is row 0, right column W−1, bottom row H−1, left column 0.
enum GridSide : int { kTop = 0, kRight = 1, kBottom = 2, kLeft = 3 };

// Texels on each side that must be vertices (positions along the side: columns for top and
// bottom, rows for left and right), e.g. the border vertices of a neighbouring omni face.
struct BorderSplits {
  std::vector<int> side[4];
};

// One tessellated grid: the texels used as vertices and the triangles over them.
struct AdaptiveGrid {
  int width = 0, height = 0;
  std::vector<std::uint32_t> vertices;  // texel ids row·W + col of the vertices, ascending
  std::vector<std::uint32_t> indices;   // three per triangle, into `vertices`, wound like the
                                        // static grid (Unprojector::standard_winding())
  std::vector<int> border[4];           // per GridSide, ascending positions of its vertices
                                        // (both corners included): what a closing or seam uses
  std::uint64_t leaves = 0;             // quadtree leaves (cells emitted)
  int fixup_rounds = 0;        // rounds of splitting leaves whose configuration broke the bound
  double balance_seconds = 0;  // threshold, balance and fix-up
  // Cells the balance and fix-up visited over all rounds: a small multiple of the quadtree's cells
  // (tessellate), or one sweep of every level per round (tessellate_by_full_rounds).
  std::uint64_t balance_visits = 0;
  double emit_seconds = 0;
  // The triangles the quadtree would have emitted when the `room` of tessellate refused them (then
  // nothing is emitted: no vertices, no indices); 0 otherwise.
  std::uint64_t refused_triangles = 0;

  std::size_t num_triangles() const { return indices.size() / 3; }
  // Index in `vertices` of texel (col, row), which must be a vertex.
  std::uint32_t vertex_index(int col, int row) const;
};

// The pyramid of a refinement measure over one grid, reusable for any number of bounds up to its
// cap. A cell's value is its measure where that is at most `cap`; above it, the value is only
// known to exceed `cap` (a cell whose child already exceeds it is not measured, and a measure
// stops at the first row past it), which decides every bound ≤ cap as the measure would. One
// build tessellates at one bound and caps there; `lightvol stats` tabulates many and does not.
class RefinementPyramid {
 public:
  RefinementPyramid(TexelDepths texels, Refinement refinement,
                    double cap = std::numeric_limits<double>::infinity());

  const TexelDepths& texels() const { return texels_; }
  Refinement refinement() const { return refinement_; }
  double seconds() const { return seconds_; }  // time to build the pyramid
  double cap() const { return cap_; }
  // Cells whose own measure was taken (wholly or up to the cap): what the cap saves, for tests
  // and benchmarks.
  std::uint64_t cells_measured() const { return cells_measured_; }
  // A cell's value, level ≥ 1, cells row-major (detail::Quadtree's numbering): for tests.
  float value(int level, std::size_t cell) const { return value_[level][cell]; }

  // Tessellates at `bound` ≤ cap() (max_error: world units; laplacian: the threshold T).
  // `standard` chooses the winding (Unprojector::standard_winding()). Deterministic; parallel.
  // `room` (may be empty) is asked, once the leaves are known, whether their triangles may be
  // emitted: if not, the grid comes back without them (AdaptiveGrid::refused_triangles).
  AdaptiveGrid tessellate(double bound, bool standard, const BorderSplits& forced = {},
                          const std::function<bool(std::uint64_t triangles)>& room = {}) const;
  // The same grid by the plain rounds: every fix-up round re-balances and re-tests the whole
  // quadtree (time: rounds × cells), measuring the texels of every leaf it tests (tessellate
  // skips the leaves whose corners and the texels' depth bounds prove them within the bound).
  // The reference tessellate is tested against.
  AdaptiveGrid tessellate_by_full_rounds(double bound, bool standard,
                                         const BorderSplits& forced = {}) const;

  // The largest world distance, over all texels, between a texel's point and its ray's point on
  // the grid's triangles (measured on the triangles themselves, not on the quadtree).
  double measure(const AdaptiveGrid& grid) const;

 private:
  AdaptiveGrid tessellate_rounds(double bound, bool standard, const BorderSplits& forced,
                                 bool full_rounds,
                                 const std::function<bool(std::uint64_t)>& room) const;
  TexelDepths texels_;
  Refinement refinement_;
  double cap_;
  std::uint64_t cells_measured_ = 0;
  int top_ = 0;                            // level of the root cell
  std::vector<std::vector<float>> value_;  // per level ≥ 1, per cell (row-major): the measure
  double seconds_ = 0;
};

}  // namespace lightvol
