#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <span>
#include <utility>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <lightvol/core/buffer.h>
#include <lightvol/core/check.h>
#include <lightvol/tessellate/collapse_grid.h>
#include <lightvol/tessellate/detail/depth_bounds.h>
#include <lightvol/tessellate/detail/lattice.h>
#include <lightvol/tessellate/detail/plane_error.h>

namespace lightvol {

namespace {

using detail::DepthBounds;
using detail::Pt;
using detail::RowSpanWalker;
using detail::span_error;
using detail::triangle_plane;
using detail::TrianglePlane;
using detail::with_texel_kind;
using detail::within_by_bounds;

std::int64_t cross(Pt a, Pt b, Pt c) {
  return std::int64_t{b.x - a.x} * (c.y - a.y) - std::int64_t{c.x - a.x} * (b.y - a.y);
}

// Whether every texel (lattice point) of the closed triangle (a, b, c) lies within `bound` of the
// triangle's plane in window depth (TexelDepths::error). Stops at the first row that breaks it.
// Rows are walked with RowSpanWalker (no division per row: most triangles here are a few texels
// wide, so the per-row work is most of the cost). Row `first_row`, when the triangle has it, is
// tested before the others: the same span and the same arithmetic as in the walk, so the answer
// is the same, only sooner where that row breaks the bound.
template <bool kUniform, class D>
[[gnu::flatten]] bool triangle_within(const TexelDepths& t, Pt a, Pt b, Pt c, double bound,
                                      int first_row) {
  const TrianglePlane plane = triangle_plane(t, a, b, c);
  const auto row_within = [&](int y, int x0, int x1) {
    const double m = span_error<kUniform, D>(t, y, x0, x1, plane.at(x0, y), plane.gx);
    return !(kUniform ? m * t.uniform_scale() > bound : m > bound);
  };
  const int y0 = std::min({a.y, b.y, c.y}), y1 = std::max({a.y, b.y, c.y});
  if (first_row >= y0 && first_row <= y1) {
    RowSpanWalker row(plane.v, first_row);
    int x0 = 0, x1 = 0;
    if (row.next(&x0, &x1) && !row_within(first_row, x0, x1)) return false;
  }
  RowSpanWalker walk(plane.v, y0);
  for (int y = y0; y <= y1; ++y) {
    int x0 = 0, x1 = 0;
    if (!walk.next(&x0, &x1) || y == first_row) continue;
    if (!row_within(y, x0, x1)) return false;
  }
  return true;
}

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
// No row to test first (triangle_within's first_row).
constexpr int kNoRow = std::numeric_limits<int>::min();

// The items k of [0, n) for which live(k) holds, each with its rank among them: counted by blocks
// in parallel, then visited by blocks in parallel (for_each(fn) calls fn(k, rank)).
template <class Live>
class LiveBlocks {
 public:
  LiveBlocks(std::size_t n, Live live) : n_(n), live_(std::move(live)), first_(blocks() + 1, 0) {
    tbb::parallel_for(std::size_t{0}, blocks(), [&](std::size_t b) {
      std::size_t count = 0;
      for (std::size_t k = b * kBlock; k < end(b); ++k) count += live_(k) ? 1 : 0;
      first_[b + 1] = count;
    });
    for (std::size_t b = 0; b < blocks(); ++b) first_[b + 1] += first_[b];
  }
  std::size_t count() const { return first_.back(); }
  template <class Fn>
  void for_each(const Fn& fn) const {
    tbb::parallel_for(std::size_t{0}, blocks(), [&](std::size_t b) {
      std::size_t at = first_[b];
      for (std::size_t k = b * kBlock; k < end(b); ++k)
        if (live_(k)) fn(k, at++);
    });
  }

 private:
  static constexpr std::size_t kBlock = std::size_t{1} << 16;
  std::size_t blocks() const { return (n_ + kBlock - 1) / kBlock; }
  std::size_t end(std::size_t b) const { return std::min(n_, (b + 1) * kBlock); }
  std::size_t n_;
  Live live_;
  std::vector<std::size_t> first_;
};

// Each vertex's star (the triangles around it), flat: one 32-byte slot a vertex (two a cache
// line) holding the count and up to kInline triangles; a larger star moves to a heap block of its
// own, owned by the slot, and stays there (collapses merge stars: nothing bounds a degree). The
// collapse's stripes change the stars of disjoint vertices in parallel: a slot is only ever
// touched by one thread at a time.
class StarTable {
 public:
  StarTable() = default;
  StarTable(const StarTable&) = delete;
  StarTable& operator=(const StarTable&) = delete;
  ~StarTable() {
    for (Slot& s : slots_)
      if (s.n & kHeap) delete[] heap(s);
  }

  // Empty stars for `nv` vertices.
  void init(std::size_t nv) { resize_large(slots_, nv); }

  // Room for `degree` triangles in v's empty star: the size it will have once filled by push().
  void reserve(std::uint32_t v, std::uint32_t degree) {
    if (degree > kInline) set_heap(&slots_[v], new std::uint32_t[degree], degree, 0);
  }

  std::span<const std::uint32_t> operator[](std::uint32_t v) const {
    const Slot& s = slots_[v];
    return {s.n & kHeap ? heap(s) : s.in, s.n & ~kHeap};
  }

  // Appends k to v's star; only v's slot (and its heap block) changes.
  void push(std::uint32_t v, std::uint32_t k) {
    Slot& s = slots_[v];
    if (!(s.n & kHeap)) {
      if (s.n < kInline) {
        s.in[s.n++] = k;
        return;
      }
      auto* block = new std::uint32_t[2 * kInline];
      std::copy(s.in, s.in + kInline, block);
      set_heap(&s, block, 2 * kInline, kInline);
    } else if ((s.n & ~kHeap) == s.in[0]) {
      const std::uint32_t size = s.n & ~kHeap;
      LV_CHECK(size < kHeap / 2);
      std::uint32_t* old = heap(s);
      auto* block = new std::uint32_t[2 * size];
      std::copy(old, old + size, block);
      delete[] old;
      set_heap(&s, block, 2 * size, size);
    }
    heap(s)[s.n++ & ~kHeap] = k;
  }

  // Removes k from v's star (it must be there), keeping the others' order.
  void erase(std::uint32_t v, std::uint32_t k) {
    Slot& s = slots_[v];
    std::uint32_t* d = s.n & kHeap ? heap(s) : s.in;
    std::uint32_t* end = d + (s.n & ~kHeap);
    std::uint32_t* at = std::find(d, end, k);
    LV_CHECK(at != end);
    std::copy(at + 1, end, at);
    --s.n;  // the size is at least 1: the flag stays
  }

  void clear(std::uint32_t v) { slots_[v].n &= kHeap; }

 private:
  static constexpr std::uint32_t kInline = 7, kHeap = 1u << 31;
  // n: the star's size; with kHeap set, the star is in a heap block: in[0] holds its capacity
  // and in[1..2] its address.
  struct alignas(32) Slot {
    std::uint32_t n;
    std::uint32_t in[kInline];
  };
  static_assert(sizeof(Slot) == 32 && sizeof(std::uint32_t*) <= 2 * sizeof(std::uint32_t));

  static std::uint32_t* heap(const Slot& s) {
    std::uint32_t* p = nullptr;
    std::memcpy(&p, &s.in[1], sizeof p);
    return p;
  }
  static void set_heap(Slot* s, std::uint32_t* block, std::uint32_t capacity, std::uint32_t size) {
    s->n = kHeap | size;
    s->in[0] = capacity;
    std::memcpy(&s->in[1], &block, sizeof block);
  }

  std::vector<Slot> slots_;
};

// The triangles' corners, three a triangle, in one flat buffer: the grid's indices themselves,
// moved in (no copy) when the caller gives the grid up.
class Corners {
 public:
  explicit Corners(std::vector<std::uint32_t> flat) : flat_(std::move(flat)) {
    LV_CHECK_EQ(flat_.size() % 3, 0u);
  }
  std::size_t size() const { return flat_.size() / 3; }
  std::span<std::uint32_t, 3> operator[](std::size_t k) {
    return std::span<std::uint32_t, 3>(flat_.data() + 3 * k, 3);
  }
  std::span<const std::uint32_t, 3> operator[](std::size_t k) const {
    return std::span<const std::uint32_t, 3>(flat_.data() + 3 * k, 3);
  }
  void set(std::size_t k, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    flat_[3 * k] = a, flat_[3 * k + 1] = b, flat_[3 * k + 2] = c;
  }

 private:
  std::vector<std::uint32_t> flat_;
};

// A copy of `values`, its pages mapped and its elements copied by all cores.
std::vector<std::uint32_t> copy_large(const std::vector<std::uint32_t>& values) {
  std::vector<std::uint32_t> copy;
  resize_large(copy, values.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, values.size(), std::size_t{1} << 16),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      std::copy(values.begin() + static_cast<std::ptrdiff_t>(r.begin()),
                                values.begin() + static_cast<std::ptrdiff_t>(r.end()),
                                copy.begin() + static_cast<std::ptrdiff_t>(r.begin()));
                    });
  return copy;
}

class Collapser {
 public:
  // `indices`: the grid's, or a copy of them (the collapse rewrites them in place).
  Collapser(const TexelDepths& texels, const AdaptiveGrid& grid, std::vector<std::uint32_t> indices,
            double bound, const CollapseOptions& options)
      : t_(texels), grid_(grid), bound_(bound), options_(options), tri_(std::move(indices)) {
    for (const std::vector<int>& keep : options.keep)
      LV_CHECK(std::is_sorted(keep.begin(), keep.end()));
    const int w = grid.width, h = grid.height;
    const std::size_t nv = grid.vertices.size(), nt = tri_.size();
    resize_large(pt_, nv);
    resize_large(sides_, nv);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 4096),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        for (std::size_t v = range.begin(); v != range.end(); ++v) {
                          const std::uint32_t id = grid.vertices[v];
                          const Pt p{static_cast<int>(id % static_cast<std::uint32_t>(w)),
                                     static_cast<int>(id / static_cast<std::uint32_t>(w))};
                          pt_[v] = p;
                          std::uint8_t s = 0;
                          if (p.y == 0) s |= 1u << kTop;
                          if (p.x == w - 1) s |= 1u << kRight;
                          if (p.y == h - 1) s |= 1u << kBottom;
                          if (p.x == 0) s |= 1u << kLeft;
                          sides_[v] = s;
                        }
                      });
    assign_large(alive_, nt, std::uint8_t{1});
    // Every triangle turns the way the first one does (the winding kept).
    const auto area2 = [&](std::size_t k) {
      const std::span<const std::uint32_t, 3> c = std::as_const(tri_)[k];
      return cross(pt_[c[0]], pt_[c[1]], pt_[c[2]]);
    };
    sign_ = area2(0) > 0 ? 1 : -1;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, 4096),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        for (std::size_t k = range.begin(); k != range.end(); ++k) {
                          const std::int64_t a = area2(k);
                          LV_CHECK(a != 0);
                          LV_CHECK((a > 0) == (sign_ > 0));
                        }
                      });
    star_.init(nv);
    // Each star in triangle order; blocks of vertices in parallel, each block reading every
    // triangle twice (its vertices' degrees, then their stars) and filling only its own
    // vertices' stars.
    const std::size_t blocks =
        static_cast<std::size_t>(std::clamp(tbb::this_task_arena::max_concurrency(), 1, 8));
    const std::size_t block = nv / blocks + 1;
    tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
      const std::uint32_t lo = static_cast<std::uint32_t>(std::min(nv, b * block)),
                          hi = static_cast<std::uint32_t>(std::min(nv, (b + 1) * block));
      std::vector<std::uint32_t> degree(hi - lo, 0);
      for (std::size_t k = 0; k < nt; ++k)
        for (int c = 0; c < 3; ++c)
          if (tri_[k][c] >= lo && tri_[k][c] < hi) ++degree[tri_[k][c] - lo];
      for (std::uint32_t v = lo; v < hi; ++v) star_.reserve(v, degree[v - lo]);
      for (std::size_t k = 0; k < nt; ++k)
        for (int c = 0; c < 3; ++c)
          if (tri_[k][c] >= lo && tri_[k][c] < hi)
            star_.push(tri_[k][c], static_cast<std::uint32_t>(k));
    });
    assign_large(vertex_alive_, nv, std::uint8_t{1});
    exact_angles_ = std::max(w, h) <= 32768 && !options.reference_flips;
    if (texels.uniform() && !options.reference_texel_tests) bounds_.build(texels);
  }

  // Sweeps. Each sweep visits its vertices in texel order, in horizontal stripes of kStripe rows,
  // each stripe in order, touching only vertices whose whole star lies inside the stripe. Such a
  // collapse changes only the triangles of that star and the stars, flags and triangles of
  // vertices inside the stripe, and a vertex's test and collapse read only its own star, so the
  // stripes are independent of each other and all run in parallel (the result is that of the
  // even stripes first, then the odd ones, as this schedule was first written). The vertices
  // whose star crossed a stripe's edge are then visited the same way in stripes shifted by half a
  // stripe (most stars that cross one stripe edge are inside a shifted stripe), and only those
  // that cross both in texel order (visit_in_order). The schedule depends on the grid alone,
  // never on the threads: same bytes.
  CollapseReport run() {
    CollapseReport r;
    const std::size_t nv = pt_.size();
    std::vector<std::uint32_t> todo;
    resize_large(todo, nv);
    for (std::size_t v = 0; v < nv; ++v) todo[v] = static_cast<std::uint32_t>(v);
    assign_large(queued_, nv, std::uint8_t{0});
    // Stripe s of a pass with offset o holds rows [s·kStripe − o, (s + 1)·kStripe − o).
    const int stripes = (grid_.height + kStripe / 2) / kStripe + 1;
    std::vector<Work> work(static_cast<std::size_t>(stripes));
    std::vector<std::uint32_t> next, crossing, left;
    while (!todo.empty() && r.rounds < options_.max_rounds) {
      ++r.rounds;
      crossing.clear();
      sweep_stripes(todo, 0, &work, &crossing);
      left.clear();
      sweep_stripes(crossing, kStripe / 2, &work, &left);
      Scratch scratch;
      if (options_.reference_order) {
        for (const std::uint32_t u : left)
          if (vertex_alive_[u] && !queued_[u]) visit(u, &scratch, &r, &next);
      } else {
        visit_in_order(left, &scratch, &r, &next);
      }
      std::size_t queued = next.size();
      for (const Work& wk : work) queued += wk.next.size();
      // The next sweep's vertices: the queued ones, in texel order (each queued once). Many: read
      // off the flags in parallel; few: sorted.
      const bool many = !options_.reference_order && queued > nv / 32;
      for (Work& wk : work) {
        if (!many) next.insert(next.end(), wk.next.begin(), wk.next.end());
        wk.next.clear();
        r.attempts += wk.report.attempts;
        r.collapses += wk.report.collapses;
        wk.report = {};
      }
      if (many) {
        take_queued(&next);
      } else {
        std::sort(next.begin(), next.end());
        for (const std::uint32_t n : next) queued_[n] = 0;
      }
      LV_CHECK_EQ(next.size(), queued);
      todo.swap(next);
      next.clear();
    }
    return r;
  }

  // Sets *out to the queued vertices in ascending order and clears their flags (blocks of
  // vertices in parallel, a word of flags at a time).
  void take_queued(std::vector<std::uint32_t>* out) {
    constexpr std::size_t kBlock = std::size_t{1} << 16;
    const std::size_t nv = queued_.size(), blocks = (nv + kBlock - 1) / kBlock;
    taken_.resize(blocks);
    tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
      std::vector<std::uint32_t>& part = taken_[b];
      part.clear();
      const std::size_t end = std::min(nv, (b + 1) * kBlock);
      std::size_t v = b * kBlock;
      for (; v + 8 <= end; v += 8) {
        std::uint64_t word = 0;
        std::memcpy(&word, &queued_[v], sizeof word);
        if (word == 0) continue;
        for (std::size_t i = v; i < v + 8; ++i)
          if (queued_[i]) part.push_back(static_cast<std::uint32_t>(i)), queued_[i] = 0;
      }
      for (; v < end; ++v)
        if (queued_[v]) part.push_back(static_cast<std::uint32_t>(v)), queued_[v] = 0;
    });
    out->clear();
    for (const std::vector<std::uint32_t>& part : taken_)
      out->insert(out->end(), part.begin(), part.end());
  }

  // Edge flips (CollapseOptions::flip_sweeps), in triangle order, sweep after sweep until one
  // flips nothing. Each flip strictly raises the smallest angle of its pair, so it ends.
  // A triangle whose three tries failed is tried again in a later sweep only if it or a triangle
  // around it changed since (a try reads only its triangle and the one across the edge, both in
  // the stars of the flipped quadrilateral's corners): the skipped tries would fail again, so the
  // flips are the same as trying every triangle in every sweep.
  std::uint64_t flip() {
    std::uint64_t flips = 0;
    assign_large(untried_, tri_.size(), std::uint8_t{1});
    const bool decided = !options_.reference_flips && !options_.reference_order;
    if (decided) assign_large(changed_, tri_.size(), std::uint8_t{0});
    for (int sweep = 0; sweep < options_.flip_sweeps; ++sweep) {
      std::uint64_t made = 0;
      std::size_t from = 0;
      while (from < tri_.size()) {
        const std::size_t to = decided ? decide_flips(from) : tri_.size();
        std::size_t at = 0;  // decisions_[at]: the next triangle decided
        for (std::size_t k = from; k < to; ++k) {
          if (!alive_[k] || (!options_.reference_flips && !untried_[k])) continue;
          const FlipDecision* dk = nullptr;
          if (decided && at < decisions_.size() && decisions_[at].k == k) dk = &decisions_[at++];
          const bool ahead = dk != nullptr;
          if (dk && changed_[k]) dk = nullptr;
          bool flipped = false;
          for (int e = 0; e < 3 && !flipped; ++e) {
            // The decision holds while neither triangle it read has changed (k unchanged and the
            // triangle across unchanged: still across; a border edge stays one).
            std::uint32_t m = dk ? dk->across[e] : kNone;
            bool allowed = false;
            if (dk && (m == kNone || !changed_[m])) {
              allowed = (dk->allowed >> e & 1) != 0;
            } else {
              m = across(static_cast<std::uint32_t>(k), e);
              allowed = flip_allowed(static_cast<std::uint32_t>(k), e, m);
              flips_redecided_ += ahead;
            }
            if (!allowed) continue;
            flip_edge(static_cast<std::uint32_t>(k), e, m);
            if (decided) {
              changed_[k] = changed_[m] = 1;
              changed_list_.push_back(static_cast<std::uint32_t>(k));
              changed_list_.push_back(m);
            }
            flipped = true;
          }
          if (flipped) {
            ++made;
          } else {
            untried_[k] = 0;
          }
        }
        for (const std::uint32_t k : changed_list_) changed_[k] = 0;
        changed_list_.clear();
        from = to;
      }
      flips += made;
      if (made == 0) break;
    }
    return flips;
  }

  std::uint64_t flips_redecided() const { return flips_redecided_; }

  AdaptiveGrid result() const {
    AdaptiveGrid out;
    out.width = grid_.width;
    out.height = grid_.height;
    // The live vertices and triangles in their order (most of the input's are gone), counted and
    // copied by blocks in parallel.
    const LiveBlocks vertices(pt_.size(), [&](std::size_t v) { return vertex_alive_[v] != 0; });
    std::vector<std::uint32_t> rank;
    resize_large(rank, pt_.size());
    out.vertices.resize(vertices.count());
    vertices.for_each([&](std::size_t v, std::size_t at) {
      rank[v] = static_cast<std::uint32_t>(at);
      out.vertices[at] = grid_.vertices[v];
    });
    const auto w = static_cast<std::uint32_t>(grid_.width);
    for (const std::uint32_t id : out.vertices) {
      const Pt p{static_cast<int>(id % w), static_cast<int>(id / w)};
      if (p.y == 0) out.border[kTop].push_back(p.x);
      if (p.y == grid_.height - 1) out.border[kBottom].push_back(p.x);
      if (p.x == 0) out.border[kLeft].push_back(p.y);
      if (p.x == grid_.width - 1) out.border[kRight].push_back(p.y);
    }
    for (const std::vector<int>& side : out.border)
      LV_CHECK(std::is_sorted(side.begin(), side.end()));
    const LiveBlocks triangles(tri_.size(), [&](std::size_t k) { return alive_[k] != 0; });
    out.indices.resize(3 * triangles.count());
    triangles.for_each([&](std::size_t k, std::size_t at) {
      for (int c = 0; c < 3; ++c) {
        LV_CHECK(vertex_alive_[tri_[k][c]]);
        out.indices[3 * at + static_cast<std::size_t>(c)] = rank[tri_[k][c]];
      }
    });
    out.leaves = grid_.leaves;
    out.fixup_rounds = grid_.fixup_rounds;
    return out;
  }

 private:
  // With `first_row`: that row's texels are tested first (triangle_within).
  bool within(Pt a, Pt b, Pt c, int first_row = kNoRow) const {
    if (!bounds_.empty() && within_by_bounds(t_, bounds_, a, b, c, bound_)) return true;
    return with_texel_kind(t_, [&](auto uniform, auto depth) {
      return triangle_within<decltype(uniform)::value, decltype(depth)>(t_, a, b, c, bound_,
                                                                        first_row);
    });
  }

  static constexpr int kStripe = 64;

  struct Scratch {
    std::vector<std::uint32_t> candidates, touched;
    std::vector<std::uint64_t> keys;
  };

  struct Work {
    Scratch scratch;
    CollapseReport report;
    std::vector<std::uint32_t> next, crossing;
    std::size_t begin = 0, end = 0;  // range of the sweep's list
  };

  // One pass over `list` (ascending: texel order) in stripes offset by `offset` rows, all in
  // parallel; appends to `crossing`, in order, the vertices whose star leaves their stripe.
  void sweep_stripes(const std::vector<std::uint32_t>& list, int offset, std::vector<Work>* work,
                     std::vector<std::uint32_t>* crossing) {
    const int stripes = static_cast<int>(work->size());
    std::size_t at = 0;
    for (int s = 0; s < stripes; ++s) {
      Work& wk = (*work)[static_cast<std::size_t>(s)];
      wk.crossing.clear();
      wk.begin = at;
      while (at < list.size() && pt_[list[at]].y < (s + 1) * kStripe - offset) ++at;
      wk.end = at;
    }
    LV_CHECK_EQ(at, list.size());
    const auto sweep = [&](int s) {
      Work& wk = (*work)[static_cast<std::size_t>(s)];
      const int y0 = s * kStripe - offset, y1 = y0 + kStripe;
      for (std::size_t i = wk.begin; i < wk.end; ++i) {
        const std::uint32_t u = list[i];
        if (!vertex_alive_[u] || queued_[u]) continue;
        if (!star_within_rows(u, y0, y1)) {
          wk.crossing.push_back(u);
          continue;
        }
        visit(u, &wk.scratch, &wk.report, &wk.next);
      }
    };
    if (options_.reference_order) {  // even stripes, then odd ones
      for (int phase = 0; phase < 2; ++phase)
        tbb::parallel_for(0, (stripes + 1 - phase) / 2, [&](int k) { sweep(2 * k + phase); });
    } else {
      tbb::parallel_for(0, stripes, sweep);
    }
    for (const Work& wk : *work)
      crossing->insert(crossing->end(), wk.crossing.begin(), wk.crossing.end());
  }

  bool star_within_rows(std::uint32_t u, int y0, int y1) const {
    for (const std::uint32_t k : star_[u])
      for (int c = 0; c < 3; ++c) {
        const int y = pt_[tri_[k][c]].y;
        if (y < y0 || y >= y1) return false;
      }
    return true;
  }

  // One attempt on u. A vertex whose star changed in this sweep waits for the next one (queued):
  // collapses spread evenly (along a step, every other vertex goes first) instead of growing one
  // star texel by texel, which would scan a chain of n vertices n²/2 times.
  void visit(std::uint32_t u, Scratch* scratch, CollapseReport* r,
             std::vector<std::uint32_t>* next) {
    const std::uint32_t v = collapse_target(u, scratch, &r->attempts);
    if (v != kNone) collapse(u, v, scratch, r, next);
  }

  // Merges u into v (collapse_target's choice) and queues the vertices whose star changed.
  void collapse(std::uint32_t u, std::uint32_t v, Scratch* scratch, CollapseReport* r,
                std::vector<std::uint32_t>* next) {
    apply(u, v, &scratch->touched);
    ++r->collapses;
    for (const std::uint32_t n : scratch->touched)
      if (!queued_[n]) queued_[n] = 1, next->push_back(n);
  }

  // The vertices of `list` whose star crosses both kinds of stripe edge, visited in order (run()'s
  // last step), deciding their collapses in parallel first. A collapse changes only the stars of
  // the vertices of the collapsing vertex's star, and queues them all (a queued vertex waits for
  // the next round). So a vertex x visited here still has the star it had when the step began,
  // and x is queued by its turn exactly when a listed vertex before it that shares a triangle with
  // it then (an earlier neighbour) collapsed: the first collapse to reach x's star must come from
  // one. The listed vertices are therefore resolved in layers (a vertex one layer after its
  // deepest earlier neighbour), in batches of whole layers: a batch's targets (collapse_target on
  // the step's mesh) decided in parallel, then the batch resolved layer by layer, a vertex whose
  // earlier neighbour collapses found queued and its target dropped (8 % of the targets decided,
  // Sibenik 4097²). Then the collapses are made in order: the same visits as one at a time.
  void visit_in_order(const std::vector<std::uint32_t>& list, Scratch* scratch, CollapseReport* r,
                      std::vector<std::uint32_t>* next) {
    const std::size_t n = list.size();
    LV_CHECK(std::is_sorted(list.begin(), list.end()));
    target_.assign(n, kNone);
    tries_.assign(n, 0);
    state_.assign(n, kPassive);
    // Each active vertex's earlier neighbours (positions in `list`, ascending: texel order), as
    // one flat table: counted, then written.
    const auto earlier = [&](std::size_t i, auto&& f) {
      const std::uint32_t u = list[i];
      for (const std::uint32_t k : star_[u])
        for (int c = 0; c < 3; ++c) {
          const std::uint32_t x = tri_[k][c];
          if (x >= u) continue;
          const auto at =
              std::lower_bound(list.begin(), list.begin() + static_cast<std::ptrdiff_t>(i), x);
          if (at != list.begin() + static_cast<std::ptrdiff_t>(i) && *at == x)
            f(static_cast<std::uint32_t>(at - list.begin()));
        }
    };
    first_.assign(n + 1, 0);
    tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
      const std::uint32_t u = list[i];
      if (!vertex_alive_[u] || queued_[u]) return;
      state_[i] = kActive;
      earlier(i, [&](std::uint32_t) { ++first_[i + 1]; });
    });
    for (std::size_t i = 0; i < n; ++i) first_[i + 1] += first_[i];
    neighbours_.resize(first_[n]);
    tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
      if (state_[i] != kActive) return;
      std::uint32_t at = first_[i];
      earlier(i, [&](std::uint32_t j) { neighbours_[at++] = j; });
    });
    // Layers, in order; each vertex's after all of its earlier neighbours'.
    layer_.assign(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
      if (state_[i] != kActive) continue;
      for (std::uint32_t a = first_[i]; a < first_[i + 1]; ++a)
        layer_[i] = std::max(layer_[i], layer_[neighbours_[a]] + 1);
    }
    by_layer_.clear();
    for (std::size_t i = 0; i < n; ++i)
      if (state_[i] == kActive) by_layer_.push_back(static_cast<std::uint32_t>(i));
    std::stable_sort(by_layer_.begin(), by_layer_.end(),
                     [&](std::uint32_t a, std::uint32_t b) { return layer_[a] < layer_[b]; });
    // Batches of whole layers, at least kBatch vertices each: the targets of a batch's vertices
    // not yet known to be queued decided in parallel, then the batch resolved layer by layer (a
    // vertex whose earlier neighbour collapses is queued, its target dropped).
    constexpr std::size_t kBatch = 64;
    const auto queued_by_earlier = [&](std::uint32_t i) {
      for (std::uint32_t a = first_[i]; a < first_[i + 1]; ++a)
        if (state_[neighbours_[a]] == kCollapses) return true;
      return false;
    };
    for (std::size_t from = 0; from < by_layer_.size();) {
      std::size_t to = from;
      while (to < by_layer_.size() &&
             (to - from < kBatch || layer_[by_layer_[to]] == layer_[by_layer_[to - 1]]))
        ++to;
      tbb::parallel_for(tbb::blocked_range<std::size_t>(from, to, 8),
                        [&](const tbb::blocked_range<std::size_t>& range) {
                          Scratch local;
                          for (std::size_t b = range.begin(); b != range.end(); ++b) {
                            const std::uint32_t i = by_layer_[b];
                            if (!queued_by_earlier(i))
                              target_[i] = collapse_target(list[i], &local, &tries_[i]);
                          }
                        });
      for (std::size_t b = from; b < to; ++b) {
        const std::uint32_t i = by_layer_[b];
        state_[i] = queued_by_earlier(i) ? kQueued : target_[i] == kNone ? kKept : kCollapses;
      }
      from = to;
    }
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t u = list[i];
      const bool visited = vertex_alive_[u] && !queued_[u];
      LV_CHECK_EQ(visited, state_[i] == kKept || state_[i] == kCollapses);
      if (!visited) continue;
      r->attempts += tries_[i];
      if (target_[i] == kNone) continue;
      collapse(u, target_[i], scratch, r, next);
      ++r->in_order_collapses;
    }
  }

  // The neighbour to merge u into (the nearest first that keeps the triangulation conforming and
  // the bound), or kNone; adds to `attempts` the candidates whose texels were evaluated. Reads u's
  // star and writes only `scratch`: safe to call for many vertices at once.
  std::uint32_t collapse_target(std::uint32_t u, Scratch* scratch, std::uint64_t* attempts) const {
    std::vector<std::uint32_t>& candidates_ = scratch->candidates;
    const std::uint8_t su = sides_[u];
    if (std::popcount(su) >= 2) return kNone;  // a corner
    int side = -1;
    if (su != 0) {
      side = std::countr_zero(su);
      if (options_.locked[side]) return kNone;
      const std::vector<int>& keep = options_.keep[side];
      const int along = side == kTop || side == kBottom ? pt_[u].x : pt_[u].y;
      if (std::binary_search(keep.begin(), keep.end(), along)) return kNone;
    }
    std::int64_t star2 = 0;
    for (const std::uint32_t k : star_[u])
      star2 += std::abs(cross(pt_[tri_[k][0]], pt_[tri_[k][1]], pt_[tri_[k][2]]));
    if (0.5 * static_cast<double>(star2) > options_.max_star_area) return kNone;
    // Neighbours of u, nearest first (ties by index: deterministic): sorted as one key each,
    // squared distance (below 2^32 for any grid an index can address) above the index.
    std::vector<std::uint64_t>& keys = scratch->keys;
    keys.clear();
    const Pt pu = pt_[u];
    for (const std::uint32_t k : star_[u])
      for (int c = 0; c < 3; ++c) {
        const std::uint32_t n = tri_[k][c];
        if (n == u) continue;
        if (side >= 0 && !(sides_[n] & (1u << side))) continue;  // border vertices slide along
        const std::int64_t dx = pt_[n].x - pu.x, dy = pt_[n].y - pu.y;
        keys.push_back(static_cast<std::uint64_t>(dx * dx + dy * dy) << 32 | n);
      }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    candidates_.clear();
    for (const std::uint64_t key : keys) candidates_.push_back(static_cast<std::uint32_t>(key));
    for (const std::uint32_t v : candidates_) {
      // Orientation first (cheap), then the texels. The new triangle over u's own texel is tested
      // first: where the bound fails, it fails there most often (the old surface passed through
      // that texel's depth), and the answer, every triangle within, is the same in any order.
      bool ok = true;
      std::uint32_t over_u = kNone;
      for (const std::uint32_t k : star_[u]) {
        const std::span<const std::uint32_t, 3> tr = std::as_const(tri_)[k];
        if (tr[0] == v || tr[1] == v || tr[2] == v) continue;
        Pt p[3];
        for (int c = 0; c < 3; ++c) p[c] = tr[c] == u ? pt_[v] : pt_[tr[c]];
        const std::int64_t a = cross(p[0], p[1], p[2]);
        if (sign_ > 0 ? a <= 0 : a >= 0) {
          ok = false;
          break;
        }
        if (over_u == kNone && covers(p, pu)) over_u = k;
        if (thin(p, a)) {
          ok = false;
          break;
        }
      }
      if (!ok) continue;
      ++*attempts;
      const auto new_within = [&](std::uint32_t k, int first_row) {
        const std::span<const std::uint32_t, 3> tr = std::as_const(tri_)[k];
        Pt p[3];
        for (int c = 0; c < 3; ++c) p[c] = tr[c] == u ? pt_[v] : pt_[tr[c]];
        return within(p[0], p[1], p[2], first_row);
      };
      if (over_u != kNone && !new_within(over_u, pu.y)) continue;
      for (const std::uint32_t k : star_[u]) {
        const std::span<const std::uint32_t, 3> tr = std::as_const(tri_)[k];
        if (k == over_u || tr[0] == v || tr[1] == v || tr[2] == v) continue;
        if (!new_within(k, kNoRow)) {
          ok = false;
          break;
        }
      }
      if (ok) return v;
    }
    return kNone;
  }

  // Whether the closed triangle p (oriented as the grid, sign_) holds the lattice point q.
  bool covers(const Pt (&p)[3], Pt q) const {
    for (int c = 0; c < 3; ++c) {
      const std::int64_t a = cross(p[c], p[(c + 1) % 3], q);
      if (sign_ > 0 ? a < 0 : a > 0) return false;
    }
    return true;
  }

  // The smallest interior angle (radians) of triangle p, q, r (texel space).
  static double min_angle(Pt p, Pt q, Pt r) {
    const Pt v[3] = {p, q, r};
    const double area2 = std::abs(static_cast<double>(cross(p, q, r)));
    double smallest = std::numbers::pi;
    for (int c = 0; c < 3; ++c) {
      const Pt a = v[c], b = v[(c + 1) % 3], d = v[(c + 2) % 3];
      const double dot = static_cast<double>(b.x - a.x) * (d.x - a.x) +
                         static_cast<double>(b.y - a.y) * (d.y - a.y);
      smallest = std::min(smallest, std::atan2(area2, dot));
    }
    return smallest;
  }

  // Whether triangle p, q, r is too thin: its height over its longest edge below min_height.
  bool thin(Pt p, Pt q, Pt r) const {
    const Pt v[3] = {p, q, r};
    return thin(v, cross(p, q, r));
  }
  // The same for triangle v whose cross product (twice its signed area) is `area2`:
  // |a| / L < h ⇔ a² < h²·L².
  bool thin(const Pt (&v)[3], std::int64_t area2) const {
    double longest2 = 0;
    for (int c = 0; c < 3; ++c) {
      const double dx = v[(c + 1) % 3].x - v[c].x, dy = v[(c + 1) % 3].y - v[c].y;
      longest2 = std::max(longest2, dx * dx + dy * dy);
    }
    const double a = static_cast<double>(area2);
    return a * a < options_.min_height * options_.min_height * longest2;
  }

  // The triangle across the edge of triangle k from corner e to corner e + 1 (kNone: a border
  // edge).
  std::uint32_t across(std::uint32_t k, int e) const {
    const std::uint32_t a = tri_[k][e], b = tri_[k][(e + 1) % 3];
    for (const std::uint32_t n : star_[a]) {
      if (n == k) continue;
      const std::span<const std::uint32_t, 3> t = std::as_const(tri_)[n];
      if (t[0] == b || t[1] == b || t[2] == b) return n;
    }
    return kNone;
  }

  // Whether CollapseOptions::flip_sweeps allows flipping the edge of triangle k from corner e to
  // corner e + 1, shared with triangle m = across(k, e) (see there). Reads triangles k and m
  // alone: safe to call for many triangles at once.
  bool flip_allowed(std::uint32_t k, int e, std::uint32_t m) const {
    if (m == kNone) return false;  // a border edge
    const std::uint32_t a = tri_[k][e], b = tri_[k][(e + 1) % 3], c = tri_[k][(e + 2) % 3];
    // The other triangle on edge a–b: (b, a, d) in the same winding.
    std::uint32_t d = kNone;
    for (const std::uint32_t x : tri_[m])
      if (x != a && x != b) d = x;
    const Pt pa = pt_[a], pb = pt_[b], pc = pt_[c], pd = pt_[d];
    // Strictly convex: both new triangles (c, a, d) and (c, d, b) turn the old way.
    const std::int64_t s1 = cross(pc, pa, pd), s2 = cross(pc, pd, pb);
    if (sign_ > 0 ? (s1 <= 0 || s2 <= 0) : (s1 >= 0 || s2 >= 0)) return false;
    // Exactly (integers) first: a flip that does not raise the smallest angle at all is refused
    // by the test on the atan2 values below as well (their error is far below its 1e-9 margin),
    // so only the flips that do raise it pay for the atan2 calls.
    if (exact_angles_ && !smallest_angle_grows(pa, pb, pc, pd)) return false;
    const double before = std::min(min_angle(pa, pb, pc), min_angle(pb, pa, pd));
    const double after = std::min(min_angle(pc, pa, pd), min_angle(pc, pd, pb));
    if (!(after > before * (1 + 1e-9))) return false;
    if (thin(pc, pa, pd) || thin(pc, pd, pb)) return false;
    return within(pc, pa, pd) && within(pc, pd, pb);
  }

  // Flips the edge of triangle k from corner e to corner e + 1, shared with m = across(k, e).
  void flip_edge(std::uint32_t k, int e, std::uint32_t m) {
    const std::uint32_t a = tri_[k][e], b = tri_[k][(e + 1) % 3], c = tri_[k][(e + 2) % 3];
    std::uint32_t d = kNone;
    for (const std::uint32_t x : tri_[m])
      if (x != a && x != b) d = x;
    tri_.set(k, c, a, d);
    tri_.set(m, c, d, b);
    star_.erase(a, m);
    star_.erase(b, k);
    star_.push(c, m);
    star_.push(d, k);
    for (const std::uint32_t v : {a, b, c, d})
      for (const std::uint32_t n : star_[v]) untried_[n] = 1;
  }

  // A flip decision made ahead: for triangle k, the triangle across each edge and whether
  // flip_allowed (bit e).
  struct FlipDecision {
    std::uint32_t k = 0;
    std::uint32_t across[3] = {kNone, kNone, kNone};
    std::uint8_t allowed = 0;
  };

  // Decides in parallel, on the mesh as it stands, the tries of the next triangles to try from
  // `from` on (alive, untried; up to kDecided of them) into decisions_, in triangle order; returns
  // the end of the range they cover. flip() then makes the flips in order, deciding again only
  // where a flip before changed one of the two triangles a decision read (changed_).
  std::size_t decide_flips(std::size_t from) {
    constexpr std::size_t kDecided = 16384;
    decisions_.clear();
    std::size_t k = from;
    for (; k < tri_.size() && decisions_.size() < kDecided; ++k)
      if (alive_[k] && (options_.reference_flips || untried_[k]))
        decisions_.push_back({static_cast<std::uint32_t>(k)});
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, decisions_.size(), 256),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        for (std::size_t i = range.begin(); i != range.end(); ++i) {
                          FlipDecision& d = decisions_[i];
                          for (int e = 0; e < 3; ++e) {
                            d.across[e] = across(d.k, e);
                            if (flip_allowed(d.k, e, d.across[e])) d.allowed |= 1u << e;
                          }
                        }
                      });
    return k;
  }

  // The sine² of a triangle's smallest angle, as a fraction: twice its area, squared, over the
  // product of its two longest edges' squared lengths (the smallest angle is at most 60°, where
  // the sine grows with the angle, and lies opposite the shortest edge). Exact in 64 bits on
  // grids up to 32768 texels a side (exact_angles_: each term below 2^62).
  struct Sine2 {
    std::int64_t num = 0, den = 1;
  };
  static Sine2 smallest_sine2(Pt p, Pt q, Pt r) {
    const auto len2 = [](Pt a, Pt b) {
      const std::int64_t dx = b.x - a.x, dy = b.y - a.y;
      return dx * dx + dy * dy;
    };
    const std::int64_t l0 = len2(p, q), l1 = len2(q, r), l2 = len2(r, p);
    const std::int64_t a = cross(p, q, r);
    const std::int64_t shortest = std::min({l0, l1, l2});
    const std::int64_t den = l0 == shortest ? l1 * l2 : l1 == shortest ? l0 * l2 : l0 * l1;
    return {a * a, den};
  }
  static bool less(Sine2 x, Sine2 y) {    // x < y, exactly
    __extension__ using Wide = __int128;  // products below 2^124
    return static_cast<Wide>(x.num) * y.den < static_cast<Wide>(y.num) * x.den;
  }
  // Whether the smallest angle of triangles (c, a, d), (c, d, b) exceeds that of (a, b, c),
  // (b, a, d), exactly.
  static bool smallest_angle_grows(Pt pa, Pt pb, Pt pc, Pt pd) {
    const Sine2 b0 = smallest_sine2(pa, pb, pc), b1 = smallest_sine2(pb, pa, pd);
    const Sine2 a0 = smallest_sine2(pc, pa, pd), a1 = smallest_sine2(pc, pd, pb);
    const Sine2 before = less(b1, b0) ? b1 : b0, after = less(a1, a0) ? a1 : a0;
    return less(before, after);
  }

  void apply(std::uint32_t u, std::uint32_t v, std::vector<std::uint32_t>* touched) {
    std::vector<std::uint32_t>& touched_ = *touched;
    touched_.clear();
    touched_.push_back(v);
    // u's star is read in place: the loop changes only the stars of u's neighbours (v among them).
    for (const std::uint32_t k : star_[u]) {
      const std::span<std::uint32_t, 3> tr = tri_[k];
      for (int c = 0; c < 3; ++c)
        if (tr[c] != u && tr[c] != v) touched_.push_back(tr[c]);
      if (tr[0] == v || tr[1] == v || tr[2] == v) {
        alive_[k] = 0;
        for (int c = 0; c < 3; ++c)
          if (tr[c] != u) star_.erase(tr[c], k);
      } else {
        for (int c = 0; c < 3; ++c)
          if (tr[c] == u) tr[c] = v;
        star_.push(v, k);
      }
    }
    star_.clear(u);
    vertex_alive_[u] = 0;
  }

  const TexelDepths& t_;
  const AdaptiveGrid& grid_;
  double bound_;
  CollapseOptions options_;
  int sign_ = 1;
  std::vector<Pt> pt_;
  std::vector<std::uint8_t> sides_;
  Corners tri_;
  std::vector<std::uint8_t> alive_, vertex_alive_;
  StarTable star_;
  std::vector<std::uint8_t> queued_;
  std::vector<std::vector<std::uint32_t>> taken_;  // take_queued(): per block of vertices
  // visit_in_order(): per listed vertex its collapse_target, attempts, state and layer; its
  // earlier neighbours (neighbours_[first_[i]], ... up to first_[i + 1]); the active ones by layer.
  enum : std::uint8_t { kPassive, kActive, kQueued, kKept, kCollapses };
  std::vector<std::uint32_t> target_;
  std::vector<std::uint64_t> tries_;
  std::vector<std::uint8_t> state_;
  std::vector<std::uint32_t> first_, neighbours_, layer_, by_layer_;
  // flip(): 1 for a triangle not tried since it or a triangle around it last changed (a byte a
  // triangle: the worst case's tables are bounded by core/limits.cpp's estimate).
  std::vector<std::uint8_t> untried_;
  // flip(): the decisions made ahead, and the triangles flipped since (a byte a triangle, and the
  // list of those set).
  std::vector<FlipDecision> decisions_;
  std::vector<std::uint8_t> changed_;
  std::vector<std::uint32_t> changed_list_;
  std::uint64_t flips_redecided_ = 0;
  bool exact_angles_ = false;
  // within_by_bounds' blocks (empty, as for non-uniform error scales: every texel test measures
  // the texels).
  DepthBounds bounds_;
};

}  // namespace

namespace {

// collapse_grid's body; `indices`: the grid's, or a copy of them.
AdaptiveGrid collapse_indices(const TexelDepths& texels, const AdaptiveGrid& grid,
                              std::vector<std::uint32_t> indices, double bound,
                              const CollapseOptions& options, CollapseReport* report) {
  const auto start = std::chrono::steady_clock::now();
  Collapser collapser(texels, grid, std::move(indices), bound, options);
  CollapseReport r = collapser.run();
  r.flips = collapser.flip();
  r.flips_redecided = collapser.flips_redecided();
  AdaptiveGrid out = collapser.result();
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  out.emit_seconds = grid.emit_seconds;
  out.balance_seconds = grid.balance_seconds;
  if (report) *report = r;
  return out;
}

}  // namespace

AdaptiveGrid collapse_grid(const TexelDepths& texels, const AdaptiveGrid& grid, double bound,
                           const CollapseOptions& options, CollapseReport* report) {
  LV_CHECK(grid.width == texels.width() && grid.height == texels.height());
  LV_CHECK(bound >= 0);
  if (grid.num_triangles() == 0) return grid;
  return collapse_indices(texels, grid, copy_large(grid.indices), bound, options, report);
}

AdaptiveGrid collapse_grid(const TexelDepths& texels, AdaptiveGrid&& grid, double bound,
                           const CollapseOptions& options, CollapseReport* report) {
  LV_CHECK(grid.width == texels.width() && grid.height == texels.height());
  LV_CHECK(bound >= 0);
  if (grid.num_triangles() == 0) return std::move(grid);
  std::vector<std::uint32_t> indices = std::move(grid.indices);
  grid.indices.clear();
  return collapse_indices(texels, grid, std::move(indices), bound, options, report);
}

GridQuality grid_quality(const AdaptiveGrid& grid) {
  GridQuality q{180.0, std::numeric_limits<double>::infinity(),
                std::numeric_limits<double>::infinity()};
  const std::uint32_t w = static_cast<std::uint32_t>(grid.width);
  for (std::size_t k = 0; k < grid.num_triangles(); ++k) {
    double x[3], y[3];
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t id = grid.vertices[grid.indices[3 * k + c]];
      x[c] = id % w, y[c] = id / w;
    }
    const double area2 = std::abs((x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]));
    q.min_area = std::min(q.min_area, 0.5 * area2);
    double longest = 0;
    for (int c = 0; c < 3; ++c)
      longest = std::max(longest, std::hypot(x[(c + 1) % 3] - x[c], y[(c + 1) % 3] - y[c]));
    q.min_height = std::min(q.min_height, area2 / longest);
    for (int c = 0; c < 3; ++c) {
      const int a = (c + 1) % 3, b = (c + 2) % 3;
      const double ux = x[a] - x[c], uy = y[a] - y[c], vx = x[b] - x[c], vy = y[b] - y[c];
      const double angle = std::atan2(area2, ux * vx + uy * vy) * 180.0 / std::numbers::pi;
      q.min_angle_degrees = std::min(q.min_angle_degrees, angle);
    }
  }
  if (grid.num_triangles() == 0) q = {};
  return q;
}

}  // namespace lightvol
