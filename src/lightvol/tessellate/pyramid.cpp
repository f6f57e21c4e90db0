// The error pyramid: each quadtree cell's own measure (max_error or laplacian), maxed with its
// children's, built once per grid; and the measure of a tessellated grid on its triangles.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <lightvol/core/buffer.h>
#include <lightvol/tessellate/adaptive_grid.h>
#include <lightvol/tessellate/detail/lattice.h>

namespace lightvol {

using detail::box_error_rows;
using detail::Pt;
using detail::Quadtree;
using detail::round_up;
using detail::seconds_since;
using detail::triangle_error;

namespace {

// Builds the pyramid's values, level by level; the steps run in the order the constructor calls
// them. value[L][cell] (L ≥ 1, cells row-major) ends as the max of the cell's own measure and its
// children's values where that is at most `cap`, and as some value above `cap` otherwise.
class PyramidBuilder {
 public:
  PyramidBuilder(const TexelDepths& texels, Refinement refinement, double cap,
                 std::vector<std::vector<float>>* value)
      : t_(texels),
        refinement_(refinement),
        cap_(cap),
        q_(texels.width(), texels.height()),
        value_(*value) {
    value_.resize(static_cast<std::size_t>(q_.top) + 1);
    for (int level = 1; level <= q_.top; ++level) {  // level 1: a quarter of the texels' count
      assign_large(value_[level], q_.cells(level), 0.0f);
    }
  }

  int top() const { return q_.top; }
  std::uint64_t measured() const { return measured_.load(); }

  // Laplacian mode: the edge map of window depth (neighbours clamped at the border).
  void edge_map();

  // Levels 1..`tile` tile by tile: a level-`tile` cell's texels stay in cache while its whole
  // sub-pyramid is computed (max_error: from the top down, see descend).
  void lower_levels(int tile);

  // max_error, the levels above `tile`: their cells' own measures in one sweep over the rows. Each
  // row adds its texels to the own measure of its cell at every upper level (partial maxima per
  // chunk of rows, joined by max: exact and deterministic), so the texels are read once more, not
  // once per level. A cell with a level-`tile` descendant above the cap is not measured: its value
  // exceeds the cap whatever its own measure.
  void upper_own_measures(int tile);

  // The levels above `tile`: the max of each cell's own measure (in place) with its children's.
  void upper_maxima(int tile);

 private:
  // One cell: its own measure (max_error: over both triangles of its unsplit configuration, up to
  // the cap; laplacian, level 1: the edge map over its texels), then the max with its children.
  // max_error calls it for level 1 only (descend does the levels above).
  void compute(int level, int i, int j);

  // max_error, one cell of a tile's sub-pyramid from the top down: its own measure, then its
  // children's values unless every descendant's own measure is known to be within the cap
  // (descendants_within); returns the cell's value. The cells below a cell so decided are not
  // measured: those of level ≥ 2 take that bound as their value (≥ their own measure, ≤ the cap:
  // unsplit, as their measure would leave them; Refiner::leaf_fails' shortcut stays sound), and
  // those of level 1 keep 0.
  float descend(int level, int i, int j, std::uint64_t* measured);

  // Whether every descendant of the whole (square) cell `b`, whose own measure is `own` and whose
  // largest |plane − depth| in window depth is `gap`, has an own measure within the cap; if so,
  // *bound is a bound on them (≤ cap). A descendant's triangle lies inside one of the cell's two
  // triangles, so on it the descendant's plane differs from the cell's by a mean of the cell's
  // plane gaps at its corners (≤ gap); the world distance along a texel's ray is a metric in
  // window depth, at most f per unit (f: the largest ray length factor over the cell and the depths
  // its planes and texels can take); so a descendant's error at a texel is at most own + gap·f.
  // With a relative margin of 1e-6 and an absolute one of 1e-12·f (the measures' rounding is some
  // 1e-16·f), the measures computed in floating point are within the cap too.
  bool descendants_within(const Quadtree::Box& b, double own, double gap, double* bound) const;

  const TexelDepths& t_;
  const Refinement refinement_;
  const double cap_;
  std::atomic<std::uint64_t> measured_{0};
  const Quadtree q_;
  std::vector<std::vector<float>>& value_;
  std::vector<float> edges_;  // laplacian: |Laplacian| per texel, rounded up
};

void PyramidBuilder::edge_map() {
  const int w = t_.width(), h = t_.height();
  edges_.resize(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
  tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
    for (int r = rows.begin(); r != rows.end(); ++r)
      for (int c = 0; c < w; ++c) {
        const auto at = [&](int cc, int rr) {
          return t_.window_depth(std::clamp(cc, 0, w - 1), std::clamp(rr, 0, h - 1));
        };
        const double lap = at(c - 1, r) + at(c + 1, r) + at(c, r - 1) + at(c, r + 1) - 4 * at(c, r);
        edges_[static_cast<std::size_t>(r) * w + c] = round_up(std::abs(lap));
      }
  });
}

void PyramidBuilder::compute(int level, int i, int j) {
  const Quadtree::Box b = q_.box(level, i, j);
  float v = 0;
  if (refinement_ == Refinement::max_error && level == 1 && b.x1 - b.x0 == 2 && b.y1 - b.y0 == 2) {
    // A whole level-1 cell: five texels, each halfway along an edge or the diagonal.
    const int x = b.x0, y = b.y0;
    const double da = t_.window_depth(x, y), db = t_.window_depth(x + 2, y),
                 dc = t_.window_depth(x, y + 2), dd = t_.window_depth(x + 2, y + 2);
    const double e =
        std::max({t_.error(x + 1, y, 0.5 * (da + db)), t_.error(x, y + 1, 0.5 * (da + dc)),
                  t_.error(x + 1, y + 1, 0.5 * (db + dc)), t_.error(x + 2, y + 1, 0.5 * (db + dd)),
                  t_.error(x + 1, y + 2, 0.5 * (dc + dd))});
    v = round_up(e);
  } else if (refinement_ == Refinement::max_error) {
    v = round_up(box_error_rows(t_, b, b.y0, b.y1 + 1, cap_));
  } else if (level == 1) {
    const int w = t_.width();
    for (int y = b.y0; y <= b.y1; ++y)
      for (int x = b.x0; x <= b.x1; ++x)
        v = std::max(v, edges_[static_cast<std::size_t>(y) * w + x]);
  }
  if (level > 1) {
    const std::vector<float>& below = value_[level - 1];
    const int nxb = q_.nx(level - 1), nyb = q_.ny(level - 1);
    for (int cj = 2 * j; cj < std::min(2 * j + 2, nyb); ++cj)
      for (int ci = 2 * i; ci < std::min(2 * i + 2, nxb); ++ci)
        v = std::max(v, below[static_cast<std::size_t>(cj) * nxb + ci]);
  }
  value_[level][static_cast<std::size_t>(j) * q_.nx(level) + i] = v;
}

bool PyramidBuilder::descendants_within(const Quadtree::Box& b, double own, double gap,
                                        double* bound) const {
  if (!std::isfinite(cap_)) return false;
  double f = 0;
  if (t_.uniform()) {
    f = t_.uniform_scale();
  } else {
    // The ray's length factor |g| is convex over the cell (g is affine in the texel): largest at
    // a corner, where scale = |g| / |w(depth)|. The depths the planes and texels take lie within
    // the corners' depths widened by `gap`; w is affine in texel and depth: its extremes over
    // that box are at its eight corners, and must not change sign.
    double lmax = 0, dmin = 1, dmax = 0;
    const int xs[2] = {b.x0, b.x1}, ys[2] = {b.y0, b.y1};
    for (const int y : ys)
      for (const int x : xs) {
        const double d = t_.window_depth(x, y);
        lmax = std::max(lmax, t_.scale_row(y)[x] * std::abs(t_.w0(x, y) + d * t_.w1()));
        dmin = std::min(dmin, d);
        dmax = std::max(dmax, d);
      }
    double wlo = std::numeric_limits<double>::infinity(), whi = -wlo;
    for (const int y : ys)
      for (const int x : xs)
        for (const double d : {dmin - gap, dmax + gap}) {
          const double w = t_.w0(x, y) + d * t_.w1();
          wlo = std::min(wlo, w);
          whi = std::max(whi, w);
        }
    const double wmin = wlo > 0 ? wlo : whi < 0 ? -whi : 0;
    if (!(wmin > 0)) return false;
    f = lmax / (wmin * wmin);
  }
  *bound = (own + gap * f) * (1 + 1e-6) + 1e-12 * f;
  return *bound <= cap_;
}

float PyramidBuilder::descend(int level, int i, int j, std::uint64_t* measured) {
  float& out = value_[level][static_cast<std::size_t>(j) * q_.nx(level) + i];
  ++*measured;
  if (level == 1) {
    compute(1, i, j);
    return out;
  }
  const Quadtree::Box b = q_.box(level, i, j);
  const int side = 1 << level;
  const bool whole = b.x1 - b.x0 == side && b.y1 - b.y0 == side;
  double gap = 0, bound = 0;
  const double own = box_error_rows(t_, b, b.y0, b.y1 + 1, cap_, whole ? &gap : nullptr);
  float v = round_up(own);
  if (whole && own <= cap_ && descendants_within(b, own, gap, &bound)) {
    const float below = round_up(bound);
    for (int l = 2; l < level; ++l) {
      const int span = 1 << (level - l), nx = q_.nx(l);
      for (int cj = j * span; cj < (j + 1) * span; ++cj)
        std::fill_n(value_[l].begin() + static_cast<std::ptrdiff_t>(cj) * nx + i * span, span,
                    below);
    }
  } else {
    const int nxb = q_.nx(level - 1), nyb = q_.ny(level - 1);
    for (int cj = 2 * j; cj < std::min(2 * j + 2, nyb); ++cj)
      for (int ci = 2 * i; ci < std::min(2 * i + 2, nxb); ++ci)
        v = std::max(v, descend(level - 1, ci, cj, measured));
  }
  out = v;
  return v;
}

void PyramidBuilder::lower_levels(int tile) {
  const int ntx = q_.nx(tile);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, q_.cells(tile)),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      std::uint64_t measured = 0;
                      for (std::size_t t = range.begin(); t != range.end(); ++t) {
                        const int ti = static_cast<int>(t % ntx), tj = static_cast<int>(t / ntx);
                        if (refinement_ == Refinement::max_error) {
                          descend(tile, ti, tj, &measured);
                          continue;
                        }
                        for (int level = 1; level <= tile; ++level) {
                          const int span = 1 << (tile - level);
                          const int i1 = std::min((ti + 1) * span, q_.nx(level)),
                                    j1 = std::min((tj + 1) * span, q_.ny(level));
                          for (int j = tj * span; j < j1; ++j)
                            for (int i = ti * span; i < i1; ++i) compute(level, i, j);
                          measured += static_cast<std::uint64_t>(j1 - tj * span) *
                                      static_cast<std::uint64_t>(i1 - ti * span);
                        }
                      }
                      measured_ += measured;
                    });
}

void PyramidBuilder::upper_own_measures(int tile) {
  const int top = q_.top;
  // past[L][cell]: a level-`tile` descendant's value exceeds the cap.
  std::vector<std::vector<std::uint8_t>> past(static_cast<std::size_t>(top) + 1);
  past[tile].resize(q_.cells(tile));
  for (std::size_t c = 0; c < past[tile].size(); ++c) past[tile][c] = value_[tile][c] > cap_;
  for (int level = tile + 1; level <= top; ++level) {
    const int nx = q_.nx(level), nxb = q_.nx(level - 1), nyb = q_.ny(level - 1);
    past[level].assign(q_.cells(level), 0);
    for (int cj = 0; cj < nyb; ++cj)
      for (int ci = 0; ci < nxb; ++ci)
        past[level][static_cast<std::size_t>(cj / 2) * nx + ci / 2] |=
            past[level - 1][static_cast<std::size_t>(cj) * nxb + ci];
  }
  using Own = std::vector<std::vector<double>>;  // per upper level, per cell
  Own empty(static_cast<std::size_t>(top) + 1);
  for (int level = tile + 1; level <= top; ++level) empty[level].assign(q_.cells(level), 0.0);
  const Own own = tbb::parallel_reduce(
      tbb::blocked_range<int>(0, t_.height(), 16), empty,
      [&](const tbb::blocked_range<int>& rows, Own acc) {
        for (int y = rows.begin(); y != rows.end(); ++y)
          for (int level = tile + 1; level <= top; ++level) {
            const int nx = q_.nx(level), ny = q_.ny(level), j = y >> level;
            for (int cj : {j - 1, j}) {
              if (cj < 0 || cj >= ny) continue;
              if (cj == j - 1 && (y & ((1 << level) - 1)) != 0) continue;  // not its bottom edge
              for (int i = 0; i < nx; ++i) {
                const std::size_t cell = static_cast<std::size_t>(cj) * nx + i;
                double& m = acc[level][cell];
                if (past[level][cell] || m > cap_) continue;
                m = std::max(m, box_error_rows(t_, q_.box(level, i, cj), y, y + 1));
              }
            }
          }
        return acc;
      },
      [](Own a, const Own& b) {
        for (std::size_t l = 0; l < a.size(); ++l)
          for (std::size_t c = 0; c < a[l].size(); ++c) a[l][c] = std::max(a[l][c], b[l][c]);
        return a;
      });
  for (int level = tile + 1; level <= top; ++level) {
    for (std::size_t c = 0; c < own[level].size(); ++c) value_[level][c] = round_up(own[level][c]);
    measured_ += static_cast<std::uint64_t>(std::count(past[level].begin(), past[level].end(), 0));
  }
}

void PyramidBuilder::upper_maxima(int tile) {
  for (int level = tile + 1; level <= q_.top; ++level) {
    const int nx = q_.nx(level), nxb = q_.nx(level - 1), nyb = q_.ny(level - 1);
    for (std::size_t cell = 0; cell < q_.cells(level); ++cell) {
      const int i = static_cast<int>(cell % nx), j = static_cast<int>(cell / nx);
      float v = value_[level][cell];
      for (int cj = 2 * j; cj < std::min(2 * j + 2, nyb); ++cj)
        for (int ci = 2 * i; ci < std::min(2 * i + 2, nxb); ++ci)
          v = std::max(v, value_[level - 1][static_cast<std::size_t>(cj) * nxb + ci]);
      value_[level][cell] = v;
    }
  }
}

}  // namespace

RefinementPyramid::RefinementPyramid(TexelDepths texels, Refinement refinement, double cap)
    : texels_(std::move(texels)), refinement_(refinement), cap_(cap) {
  const auto start = std::chrono::steady_clock::now();
  PyramidBuilder builder(texels_, refinement_, cap_, &value_);
  top_ = builder.top();
  if (refinement_ == Refinement::laplacian) builder.edge_map();
  const int tile = std::min(top_, 6);
  if (tile >= 1) builder.lower_levels(tile);
  if (top_ > tile && refinement_ == Refinement::max_error) builder.upper_own_measures(tile);
  builder.upper_maxima(tile);
  cells_measured_ = builder.measured();
  seconds_ = seconds_since(start);
}

double RefinementPyramid::measure(const AdaptiveGrid& grid) const {
  const std::uint32_t w = static_cast<std::uint32_t>(grid.width);
  const auto pt = [&](std::uint32_t v) {
    const std::uint32_t id = grid.vertices[v];
    return Pt{static_cast<int>(id % w), static_cast<int>(id / w)};
  };
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, grid.num_triangles(), 256), 0.0,
      [&](const tbb::blocked_range<std::size_t>& r, double m) {
        for (std::size_t t = r.begin(); t != r.end(); ++t)
          m = std::max(m, triangle_error(texels_, pt(grid.indices[3 * t]),
                                         pt(grid.indices[3 * t + 1]), pt(grid.indices[3 * t + 2])));
        return m;
      },
      [](double a, double b) { return std::max(a, b); });
}

}  // namespace lightvol
