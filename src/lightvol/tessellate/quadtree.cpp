// Quadtree refinement and emission: RefinementPyramid::tessellate thresholds the pyramid at a
// bound, forces border vertices, balances the quadtree 2:1, splits leaves whose configuration
// breaks the bound, and emits the leaves' triangles over the texels used as vertices.
#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <chrono>
#include <cstdint>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <lightvol/core/buffer.h>
#include <lightvol/core/check.h>
#include <lightvol/tessellate/adaptive_grid.h>
#include <lightvol/tessellate/detail/depth_bounds.h>
#include <lightvol/tessellate/detail/lattice.h>

namespace lightvol {

using detail::cell_triangles;
using detail::DepthBounds;
using detail::kSplitBottom;
using detail::kSplitLeft;
using detail::kSplitRight;
using detail::kSplitTop;
using detail::Pt;
using detail::Quadtree;
using detail::seconds_since;
using detail::triangle_error;
using detail::within_by_bounds;

std::uint32_t AdaptiveGrid::vertex_index(int col, int row) const {
  const std::uint32_t id = static_cast<std::uint32_t>(row) * static_cast<std::uint32_t>(width) +
                           static_cast<std::uint32_t>(col);
  const auto it = std::lower_bound(vertices.begin(), vertices.end(), id);
  LV_CHECK(it != vertices.end() && *it == id);
  return static_cast<std::uint32_t>(it - vertices.begin());
}

namespace {

// The set bits of x. std::popcount is a call into libgcc where the POPCNT instruction is not in
// the target (the x86-64 baseline this builds for); this count inlines (the emission ranks some
// 75 million triangle corners at 16384²).
inline int count_bits(std::uint64_t x) {
#if defined(__POPCNT__)
  return std::popcount(x);
#else
  x -= (x >> 1) & 0x5555555555555555u;
  x = (x & 0x3333333333333333u) + ((x >> 2) & 0x3333333333333333u);
  x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0fu;
  return static_cast<int>((x * 0x0101010101010101u) >> 56);
#endif
}

// One tessellation at one bound: which cells are split, and the steps that decide it and emit the
// leaves. The steps run in the order tessellate calls them.
class Refiner {
 public:
  Refiner(const TexelDepths& texels, const std::vector<std::vector<float>>& value, double bound)
      : texels_(texels), value_(value), bound_(bound), q_(texels.width(), texels.height()) {}

  // A cell splits where its pyramid value exceeds the bound.
  void threshold();
  // Forced border vertices: splits every cell along the side whose interior holds the texel.
  void force_border(const BorderSplits& forced);
  // 2:1 balance: a split cell needs its four same-level neighbours to exist, so their parents
  // split; and a split cell's parent splits. One sweep from fine to coarse settles every level.
  void balance();
  // The same closure after the cells in changed_ from index `from` on were split: each split only
  // visits its parent and its neighbours' parents, and whatever it splits is appended to changed_
  // and visited in turn. Time: linear in the cells it splits.
  void balance_from(std::size_t from);
  // max_error's fix-up: splits the leaves whose split configuration breaks the bound (their
  // children meet it with their own triangles: the pyramid's values never grow downwards), and
  // appends them to changed_. Returns whether any leaf split. Tests every leaf.
  bool split_failing_leaves();
  // The same, testing only the leaves whose test can have changed since the previous round: the
  // children and same-level neighbours of the cells in changed_ (a leaf whose own cell, parent and
  // neighbours kept their state has the configuration it passed with). Clears changed_ first.
  bool split_failing_changed_leaves();
  // The texels' depth bounds for leaf_fails' shortcut from now on (null: every tested leaf's texels
  // measured).
  void use_bounds(const DepthBounds* bounds) { bounds_ = bounds; }
  // Cells the balance and fix-up visited (sweeps: every cell of the levels swept).
  std::uint64_t visits() const { return visits_; }
  // Emission: the vertex bitmap and triangle counts, the vertices ranked in texel order, the
  // triangles (wound as `standard` says), and the border vertices per side.
  // The leaves' triangles into `grid`, unless `room` (if any) refuses their number.
  void emit(bool standard, AdaptiveGrid* grid, const std::function<bool(std::uint64_t)>& room);

 private:
  // Leaves come by blocks: a block is one row of level-(L+1) cells, whose unsplit children are the
  // leaves of level L there (the root alone for the top level). Order: coarse levels first, rows
  // and cells in order: deterministic.
  struct Block {
    int level, row;
  };
  std::vector<Block> blocks() const;

  bool is_split(int level, int i, int j) const {
    if (level < 1 || i < 0 || j < 0 || i >= q_.nx(level) || j >= q_.ny(level)) return false;
    return split_[level][static_cast<std::size_t>(j) * q_.nx(level) + i] != 0;
  }
  void set_split(int level, int i, int j) {
    split_[level][static_cast<std::size_t>(j) * q_.nx(level) + i] = 1;
  }
  // Configuration of a leaf: the edges whose same-level neighbour is split and whose midpoint is
  // a texel inside the (clipped) edge.
  unsigned config_of(int level, int i, int j, const Quadtree::Box& b) const;
  // Whether the leaf's split configuration breaks the bound.
  bool leaf_fails(int level, int i, int j) const;
  // Splits the cells (level ≥ 2) marked in fail and appends them to changed_.
  void split_marked(const std::vector<std::vector<std::uint8_t>>& fail);
  // Calls fn(i, j) for each leaf of block `blk`, in order.
  template <typename Fn>
  void for_each_leaf(const Block& blk, Fn&& fn) const;

  // The bitmap of the texels that are vertices, one bit per texel, rows padded to 64-bit words.
  struct VertexBits {
    std::size_t words = 0;  // per row
    std::vector<std::uint64_t> used;
    std::vector<std::uint32_t> word_rank;  // vertices before each word
    bool has(int col, int row) const {
      return (used[static_cast<std::size_t>(row) * words + col / 64] >> (col % 64)) & 1;
    }
    // The index of vertex p among the vertices in texel order (row-major).
    std::uint32_t rank(Pt p) const {
      const std::size_t k = static_cast<std::size_t>(p.y) * words + p.x / 64;
      const std::uint64_t below = (std::uint64_t{1} << (p.x % 64)) - 1;
      return word_rank[k] + static_cast<std::uint32_t>(count_bits(used[k] & below));
    }
  };
  // Marks every leaf's corners and split midpoints as vertices; returns each block's first
  // triangle (a prefix sum, with the total last) and adds the leaves to grid->leaves.
  std::vector<std::uint64_t> mark_vertices(const std::vector<Block>& blocks, VertexBits* bits,
                                           AdaptiveGrid* grid) const;
  // grid->vertices: the marked texels' ids in ascending order; fills bits->word_rank.
  void rank_vertices(VertexBits* bits, AdaptiveGrid* grid) const;
  // grid->indices: each leaf's triangles, block k's from its first triangle on.
  void write_triangles(const std::vector<Block>& blocks,
                       const std::vector<std::uint64_t>& first_triangle, const VertexBits& bits,
                       bool standard, AdaptiveGrid* grid) const;

  const TexelDepths& texels_;
  const std::vector<std::vector<float>>& value_;
  const double bound_;
  const DepthBounds* bounds_ = nullptr;
  const Quadtree q_;
  // split_[L][cell]: the cell (level ≥ 1) is divided into its children.
  std::vector<std::vector<std::uint8_t>> split_;
  // Cells split since the leaves were last tested, by the fix-up or the balance it caused.
  struct Cell {
    int level, i, j;
  };
  std::vector<Cell> changed_;
  // split_failing_changed_leaves' flags of the cells (level ≥ 2) taken as candidates: all clear
  // between calls; allocated by the first.
  std::vector<std::vector<std::uint8_t>> candidate_;
  std::uint64_t visits_ = 0;
};

void Refiner::threshold() {
  split_.assign(static_cast<std::size_t>(q_.top) + 1, {});
  for (int level = 1; level <= q_.top; ++level) {
    const std::vector<float>& v = value_[level];
    std::vector<std::uint8_t>& s = split_[level];
    resize_large(s, v.size());
    for (std::size_t c = 0; c < v.size(); ++c) s[c] = v[c] > bound_ ? 1 : 0;
  }
}

void Refiner::force_border(const BorderSplits& forced) {
  for (int side = 0; side < 4; ++side) {
    const int length = (side == kTop || side == kBottom) ? q_.cw : q_.ch;
    for (const int p : forced.side[side]) {
      LV_CHECK(p >= 0 && p <= length);
      if (p == 0 || p == length) continue;
      for (int level = q_.top; level >= 1 && (p & ((1 << level) - 1)) != 0; --level) {
        const int k = p >> level;
        switch (side) {
          case kTop:
            set_split(level, k, 0);
            break;
          case kBottom:
            set_split(level, k, q_.ny(level) - 1);
            break;
          case kLeft:
            set_split(level, 0, k);
            break;
          default:
            set_split(level, q_.nx(level) - 1, k);
            break;
        }
      }
    }
  }
}

unsigned Refiner::config_of(int level, int i, int j, const Quadtree::Box& b) const {
  if (level == 0) return 0u;
  const int half = 1 << (level - 1);
  unsigned config = 0;
  if (b.x0 + half < b.x1) {
    if (is_split(level, i, j - 1)) config |= kSplitTop;
    if (is_split(level, i, j + 1)) config |= kSplitBottom;
  }
  if (b.y0 + half < b.y1) {
    if (is_split(level, i - 1, j)) config |= kSplitLeft;
    if (is_split(level, i + 1, j)) config |= kSplitRight;
  }
  return config;
}

std::vector<Refiner::Block> Refiner::blocks() const {
  std::vector<Block> blocks{{q_.top, 0}};
  for (int level = q_.top - 1; level >= 0; --level)
    for (int j = 0; j < q_.ny(level + 1); ++j) blocks.push_back({level, j});
  return blocks;
}

template <typename Fn>
void Refiner::for_each_leaf(const Block& blk, Fn&& fn) const {
  const int level = blk.level;
  if (level == q_.top) {
    if (!is_split(q_.top, 0, 0)) fn(0, 0);
    return;
  }
  const int pnx = q_.nx(level + 1), nx = q_.nx(level), ny = q_.ny(level);
  const std::uint8_t* prow = split_[level + 1].data() + static_cast<std::size_t>(blk.row) * pnx;
  for (int pi = 0; pi < pnx; ++pi) {
    if (!prow[pi]) continue;
    for (int cj = 2 * blk.row; cj < std::min(2 * blk.row + 2, ny); ++cj)
      for (int ci = 2 * pi; ci < std::min(2 * pi + 2, nx); ++ci)
        if (!is_split(level, ci, cj)) fn(ci, cj);
  }
}

void Refiner::balance() {
  for (int level = 2; level <= q_.top; ++level) {
    const int nx = q_.nx(level);
    std::vector<std::uint8_t>& s = split_[level];
    visits_ += s.size();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, s.size(), 1024),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        for (std::size_t cell = range.begin(); cell != range.end(); ++cell) {
                          if (s[cell]) continue;
                          const int i = static_cast<int>(cell % nx),
                                    j = static_cast<int>(cell / nx);
                          const int l = level - 1, ci = 2 * i, cj = 2 * j;
                          const bool any = is_split(l, ci, cj) || is_split(l, ci + 1, cj) ||
                                           is_split(l, ci, cj + 1) || is_split(l, ci + 1, cj + 1) ||
                                           is_split(l, ci - 1, cj) || is_split(l, ci - 1, cj + 1) ||
                                           is_split(l, ci + 2, cj) || is_split(l, ci + 2, cj + 1) ||
                                           is_split(l, ci, cj - 1) || is_split(l, ci + 1, cj - 1) ||
                                           is_split(l, ci, cj + 2) || is_split(l, ci + 1, cj + 2);
                          if (any) s[cell] = 1;
                        }
                      });
  }
}

void Refiner::balance_from(std::size_t from) {
  const auto force = [&](int level, int i, int j) {  // the level-(level+1) parent of (i, j)
    if (i < 0 || j < 0 || i >= q_.nx(level) || j >= q_.ny(level)) return;
    const int pl = level + 1, pi = i >> 1, pj = j >> 1;
    if (is_split(pl, pi, pj)) return;
    set_split(pl, pi, pj);
    changed_.push_back({pl, pi, pj});
  };
  for (std::size_t k = from; k < changed_.size(); ++k) {
    const Cell c = changed_[k];
    ++visits_;
    if (c.level >= q_.top) continue;
    force(c.level, c.i, c.j);
    force(c.level, c.i - 1, c.j);
    force(c.level, c.i + 1, c.j);
    force(c.level, c.i, c.j - 1);
    force(c.level, c.i, c.j + 1);
  }
}

bool Refiner::leaf_fails(int level, int i, int j) const {
  // Level 1 never fails: every configuration keeps the diagonal, and the texels that are not
  // vertices (unsplit edge midpoints, the centre on the diagonal) interpolate as in the unsplit
  // cell.
  if (level <= 1) return false;
  const Quadtree::Box b = q_.box(level, i, j);
  const unsigned config = config_of(level, i, j, b);
  if (config == 0) return false;
  // With a uniform error scale, a configuration moves the surface by at most the deviation of its
  // split midpoints, texels of the cell: its error is at most twice the cell's own (≤ its pyramid
  // value v). 2v within the bound needs no evaluation.
  const double v = value_[level][static_cast<std::size_t>(j) * q_.nx(level) + i];
  if (texels_.uniform() && 2 * v * (1 + 1e-9) <= bound_) return false;
  std::array<Pt, 3> tri[6];
  const int n = cell_triangles(b, 1 << (level - 1), config, tri);
  // A triangle the depth bounds prove within the bound needs no measure (within_by_bounds: never
  // a triangle triangle_error would find beyond it).
  for (int t = 0; t < n; ++t) {
    if (bounds_ && within_by_bounds(texels_, *bounds_, tri[t][0], tri[t][1], tri[t][2], bound_))
      continue;
    if (triangle_error(texels_, tri[t][0], tri[t][1], tri[t][2]) > bound_) return true;
  }
  return false;
}

void Refiner::split_marked(const std::vector<std::vector<std::uint8_t>>& fail) {
  for (int level = 2; level <= q_.top; ++level) {
    const int nx = q_.nx(level);
    for (std::size_t c = 0; c < fail[level].size(); ++c) {
      if (!fail[level][c]) continue;
      split_[level][c] = 1;
      changed_.push_back({level, static_cast<int>(c % nx), static_cast<int>(c / nx)});
    }
  }
}

bool Refiner::split_failing_leaves() {
  const std::vector<Block> blks = blocks();
  std::vector<std::vector<std::uint8_t>> fail(split_.size());
  for (int level = 2; level <= q_.top; ++level) {
    assign_large(fail[level], split_[level].size(), std::uint8_t{0});
    visits_ += split_[level].size();
  }
  const bool any_fail = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, blks.size(), 1), false,
      [&](const tbb::blocked_range<std::size_t>& range, bool acc) {
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
          const int level = blks[k].level;
          if (level <= 1) continue;
          for_each_leaf(blks[k], [&](int i, int j) {
            if (!leaf_fails(level, i, j)) return;
            fail[level][static_cast<std::size_t>(j) * q_.nx(level) + i] = 1;
            acc = true;
          });
        }
        return acc;
      },
      [](bool a, bool b) { return a || b; });
  changed_.clear();
  if (any_fail) split_marked(fail);
  return any_fail;
}

bool Refiner::split_failing_changed_leaves() {
  // The candidates, as (level, cell index) keys, each once (a flag per cell marks those taken; the
  // flags are cleared again below), in the order changed_ reaches them: the leaves are tested
  // against the tree as this round found it and split after all tests, so the order changes
  // nothing but the work's locality, which this order keeps (a changed cell's candidates are its
  // children and neighbours).
  if (candidate_.empty()) {
    candidate_.resize(split_.size());
    for (int level = 2; level <= q_.top; ++level)
      assign_large(candidate_[level], split_[level].size(), std::uint8_t{0});
  }
  std::vector<std::uint64_t> keys;
  const auto add = [&](int level, int i, int j) {
    if (level < 2 || i < 0 || j < 0 || i >= q_.nx(level) || j >= q_.ny(level)) return;
    const std::size_t cell = static_cast<std::size_t>(j) * static_cast<std::size_t>(q_.nx(level)) +
                             static_cast<std::size_t>(i);
    std::uint8_t& taken = candidate_[level][cell];
    if (taken) return;
    taken = 1;
    keys.push_back((static_cast<std::uint64_t>(level) << 58) | cell);
  };
  for (const Cell& c : changed_) {
    for (int dj = 0; dj < 2; ++dj)
      for (int di = 0; di < 2; ++di) add(c.level - 1, 2 * c.i + di, 2 * c.j + dj);
    add(c.level, c.i - 1, c.j);
    add(c.level, c.i + 1, c.j);
    add(c.level, c.i, c.j - 1);
    add(c.level, c.i, c.j + 1);
  }
  changed_.clear();
  for (const std::uint64_t key : keys)
    candidate_[key >> 58][key & ((std::uint64_t{1} << 58) - 1)] = 0;
  visits_ += keys.size();
  std::vector<std::uint8_t> fails(keys.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, keys.size(), 64),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t k = range.begin(); k != range.end(); ++k) {
                        const int level = static_cast<int>(keys[k] >> 58);
                        const std::uint64_t cell = keys[k] & ((std::uint64_t{1} << 58) - 1);
                        const int nx = q_.nx(level);
                        const int i = static_cast<int>(cell % static_cast<std::uint64_t>(nx)),
                                  j = static_cast<int>(cell / static_cast<std::uint64_t>(nx));
                        const bool leaf = !is_split(level, i, j) &&
                                          (level == q_.top || is_split(level + 1, i / 2, j / 2));
                        fails[k] = leaf && leaf_fails(level, i, j) ? 1 : 0;
                      }
                    });
  bool any_fail = false;
  for (std::size_t k = 0; k < keys.size(); ++k) {
    if (!fails[k]) continue;
    any_fail = true;
    const int level = static_cast<int>(keys[k] >> 58);
    const std::uint64_t cell = keys[k] & ((std::uint64_t{1} << 58) - 1);
    const int nx = q_.nx(level);
    split_[level][cell] = 1;
    changed_.push_back({level, static_cast<int>(cell % static_cast<std::uint64_t>(nx)),
                        static_cast<int>(cell / static_cast<std::uint64_t>(nx))});
  }
  return any_fail;
}

std::vector<std::uint64_t> Refiner::mark_vertices(const std::vector<Block>& blocks,
                                                  VertexBits* bits, AdaptiveGrid* grid) const {
  const int w = texels_.width(), h = texels_.height();
  std::vector<std::uint64_t> block_triangles(blocks.size() + 1, 0), block_leaves(blocks.size(), 0);
  bits->words = (static_cast<std::size_t>(w) + 63) / 64;
  assign_large(bits->used, bits->words * static_cast<std::size_t>(h), std::uint64_t{0});
  const auto mark = [&](Pt p) {
    std::atomic_ref<std::uint64_t> word(
        bits->used[static_cast<std::size_t>(p.y) * bits->words + p.x / 64]);
    const std::uint64_t bit = std::uint64_t{1} << (p.x % 64);
    if ((word.load(std::memory_order_relaxed) & bit) == 0)
      word.fetch_or(bit, std::memory_order_relaxed);
  };
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, blocks.size()),
      [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
          const int level = blocks[k].level;
          std::uint64_t tris = 0, leaves = 0;
          for_each_leaf(blocks[k], [&](int i, int j) {
            const Quadtree::Box b = q_.box(level, i, j);
            const unsigned config = config_of(level, i, j, b);
            ++leaves;
            tris += 2 + static_cast<unsigned>(count_bits(config));
            mark({b.x0, b.y0}), mark({b.x1, b.y0}), mark({b.x0, b.y1}), mark({b.x1, b.y1});
            const int half = level > 0 ? 1 << (level - 1) : 0;
            if (config & kSplitTop) mark({b.x0 + half, b.y0});
            if (config & kSplitBottom) mark({b.x0 + half, b.y1});
            if (config & kSplitLeft) mark({b.x0, b.y0 + half});
            if (config & kSplitRight) mark({b.x1, b.y0 + half});
          });
          block_triangles[k + 1] = tris;
          block_leaves[k] = leaves;
        }
      });
  for (std::size_t k = 0; k < blocks.size(); ++k) {
    block_triangles[k + 1] += block_triangles[k];
    grid->leaves += block_leaves[k];
  }
  return block_triangles;
}

void Refiner::rank_vertices(VertexBits* bits, AdaptiveGrid* grid) const {
  const int w = texels_.width(), h = texels_.height();
  const std::vector<std::uint64_t>& used = bits->used;
  std::vector<std::uint32_t>& word_rank = bits->word_rank;
  assign_large(word_rank, used.size() + 1, std::uint32_t{0});
  for (std::size_t k = 0; k < used.size(); ++k)
    word_rank[k + 1] = word_rank[k] + static_cast<std::uint32_t>(count_bits(used[k]));
  resize_large(grid->vertices, word_rank.back());
  const std::size_t words = bits->words;
  tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
    for (int r = rows.begin(); r != rows.end(); ++r)
      for (std::size_t wd = 0; wd < words; ++wd) {
        const std::size_t k = static_cast<std::size_t>(r) * words + wd;
        std::uint32_t at = word_rank[k];
        for (std::uint64_t b = used[k]; b; b &= b - 1) {
          const int col = static_cast<int>(wd * 64) + std::countr_zero(b);
          grid->vertices[at++] = static_cast<std::uint32_t>(r) * static_cast<std::uint32_t>(w) +
                                 static_cast<std::uint32_t>(col);
        }
      }
  });
}

void Refiner::write_triangles(const std::vector<Block>& blocks,
                              const std::vector<std::uint64_t>& first_triangle,
                              const VertexBits& bits, bool standard, AdaptiveGrid* grid) const {
  resize_large(grid->indices, 3 * first_triangle.back());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size()),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t k = range.begin(); k != range.end(); ++k) {
                        const int level = blocks[k].level;
                        std::uint32_t* out = grid->indices.data() + 3 * first_triangle[k];
                        for_each_leaf(blocks[k], [&](int i, int j) {
                          const Quadtree::Box b = q_.box(level, i, j);
                          std::array<Pt, 3> tri[6];
                          const int n = cell_triangles(b, level > 0 ? 1 << (level - 1) : 0,
                                                       config_of(level, i, j, b), tri);
                          for (int t = 0; t < n; ++t) {
                            const std::uint32_t a = bits.rank(tri[t][0]), bb = bits.rank(tri[t][1]),
                                                c = bits.rank(tri[t][2]);
                            if (standard) {
                              *out++ = a, *out++ = bb, *out++ = c;
                            } else {
                              *out++ = a, *out++ = c, *out++ = bb;
                            }
                          }
                        });
                        LV_CHECK_EQ(out, grid->indices.data() + 3 * first_triangle[k + 1]);
                      }
                    });
}

void Refiner::emit(bool standard, AdaptiveGrid* grid,
                   const std::function<bool(std::uint64_t)>& room) {
  const int w = texels_.width(), h = texels_.height();
  const std::vector<Block> blks = blocks();
  VertexBits bits;
  const std::vector<std::uint64_t> first_triangle = mark_vertices(blks, &bits, grid);
  if (room && !room(first_triangle.back())) {
    grid->refused_triangles = first_triangle.back();
    return;
  }
  rank_vertices(&bits, grid);
  write_triangles(blks, first_triangle, bits, standard, grid);
  for (int c = 0; c < w; ++c) {
    if (bits.has(c, 0)) grid->border[kTop].push_back(c);
    if (bits.has(c, h - 1)) grid->border[kBottom].push_back(c);
  }
  for (int r = 0; r < h; ++r) {
    if (bits.has(w - 1, r)) grid->border[kRight].push_back(r);
    if (bits.has(0, r)) grid->border[kLeft].push_back(r);
  }
}

}  // namespace

AdaptiveGrid RefinementPyramid::tessellate(double bound, bool standard, const BorderSplits& forced,
                                           const std::function<bool(std::uint64_t)>& room) const {
  return tessellate_rounds(bound, standard, forced, false, room);
}

AdaptiveGrid RefinementPyramid::tessellate_by_full_rounds(double bound, bool standard,
                                                          const BorderSplits& forced) const {
  return tessellate_rounds(bound, standard, forced, true, {});
}

AdaptiveGrid RefinementPyramid::tessellate_rounds(
    double bound, bool standard, const BorderSplits& forced, bool full_rounds,
    const std::function<bool(std::uint64_t)>& room) const {
  LV_CHECK(bound <= cap_);  // values above the cap only say they exceed it
  const auto start = std::chrono::steady_clock::now();
  AdaptiveGrid grid;
  grid.width = texels_.width();
  grid.height = texels_.height();
  Refiner refiner(texels_, value_, bound);
  refiner.threshold();
  refiner.force_border(forced);
  // Balance, then (max_error) split the leaves that break the bound, until none does. The first
  // round sweeps and tests the whole tree; each later one (unless full_rounds) only propagates the
  // splits of the round before and re-tests the leaves they touched: the same rounds, the same
  // splits, in time linear in the quadtree's size however many rounds a map takes.
  refiner.balance();
  DepthBounds bounds;
  if (refinement_ == Refinement::max_error) {
    for (bool first = true;; first = false) {
      const bool split = first || full_rounds ? refiner.split_failing_leaves()
                                              : refiner.split_failing_changed_leaves();
      if (!split) break;
      ++grid.fixup_rounds;
      // Once a round split leaves (rounds may cascade), the later rounds' leaf tests first try
      // the texels' depth bounds (uniform error scales; the plain full rounds measure every leaf
      // they test); a map whose first round splits nothing never builds them.
      if (first && !full_rounds && texels_.uniform()) {
        bounds.build(texels_);
        refiner.use_bounds(&bounds);
      }
      if (full_rounds) {
        refiner.balance();
      } else {
        refiner.balance_from(0);
      }
    }
  }
  grid.balance_seconds = seconds_since(start);
  grid.balance_visits = refiner.visits();
  const auto emit_start = std::chrono::steady_clock::now();
  refiner.emit(standard, &grid, room);
  grid.emit_seconds = seconds_since(emit_start);
  return grid;
}

}  // namespace lightvol
