// Closed, edge-manifold, oriented: every edge's uses, bucketed by the edge's lower vertex in
// chunks of vertices small enough to stay in cache, each bucket sorted and read in turn.
//
// An edge use is 4 bytes (the upper vertex and the direction) instead of a sortable record of
// the whole mesh: the uses of one chunk of lower vertices are counted, placed and checked, then
// the same buffer serves the next chunk. A chunk reads only the blocks of faces whose edges can
// have their lower vertex in it, so meshes whose faces come in vertex order (grids: every volume
// `build` makes) are read about twice in all, whatever the number of chunks; when the faces are in
// no such order, fewer and larger chunks keep the reading linear.
#include <algorithm>
#include <array>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <lightvol/check/detail/linear_checks.h>

namespace lightvol::detail {
namespace {

constexpr std::size_t kBlockFaces = 1024;
// Edge uses per chunk: 256 K (1 MiB of 4-byte uses, and about 1 MiB of the faces they come from)
// stay in a core's cache between counting, placing and checking them.
constexpr std::size_t kChunkUses = std::size_t{1} << 18;
// How many times all the faces may be read by the chunks' count and fill passes together, over
// the two that a single chunk needs, before the chunks are made larger.
constexpr std::size_t kMaxReads = 3;

// The lower vertices of the edges of a block of faces lie in [lo_min, lo_max]: from the least
// vertex of a face to the greatest middle one.
struct BlockRange {
  std::uint32_t lo_min, lo_max;
};

std::vector<BlockRange> block_ranges(const Mesh& mesh) {
  const std::size_t nt = mesh.num_triangles();
  const std::uint32_t* idx = mesh.indices.data();
  std::vector<BlockRange> blocks((nt + kBlockFaces - 1) / kBlockFaces);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, blocks.size(), 16),
      [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t b = r.begin(); b != r.end(); ++b) {
          BlockRange range{std::numeric_limits<std::uint32_t>::max(), 0};
          const std::size_t end = std::min(nt, (b + 1) * kBlockFaces);
          for (std::size_t t = b * kBlockFaces; t < end; ++t) {
            const std::uint32_t x = idx[3 * t], y = idx[3 * t + 1], z = idx[3 * t + 2];
            const std::uint32_t lo = std::min({x, y, z});
            const std::uint32_t mid = std::max(std::min(x, y), std::min(std::max(x, y), z));
            range.lo_min = std::min(range.lo_min, lo);
            range.lo_max = std::max(range.lo_max, mid);
          }
          blocks[b] = range;
        }
      });
  return blocks;
}

// Chunk k holds the lower vertices [first(k), first(k + 1)) of `chunks` equal ranges.
struct Chunking {
  std::size_t nv = 0, chunks = 1;
  std::size_t of(std::uint64_t v) const { return static_cast<std::size_t>(v * chunks / nv); }
  std::size_t first(std::size_t k) const { return (k * nv + chunks - 1) / chunks; }
};

// The most chunks (of at most kChunkUses uses each, if the uses were spread evenly) whose blocks
// add up to at most kMaxReads readings of the faces.
Chunking choose_chunking(const Mesh& mesh, const std::vector<BlockRange>& blocks) {
  Chunking c;
  c.nv = mesh.num_vertices();
  const std::size_t uses = 3 * mesh.num_triangles();
  std::size_t chunks =
      std::min(c.nv, std::max<std::size_t>(1, (uses + kChunkUses - 1) / kChunkUses));
  for (; chunks > 1; chunks /= 2) {
    Chunking trial{c.nv, chunks};
    std::size_t reads = 0;
    for (const BlockRange& b : blocks) reads += trial.of(b.lo_max) - trial.of(b.lo_min) + 1;
    if (reads <= kMaxReads * blocks.size()) break;
  }
  c.chunks = std::max<std::size_t>(chunks, 1);
  return c;
}

// An undirected edge and, for a boundary edge, its direction in its face.
struct EdgeFound {
  std::uint32_t from, to;
};

// What one chunk of lower vertices found, in (lower, upper) vertex order.
struct ChunkFound {
  std::vector<EdgeFound> boundary;  // all of them, directed as in their face
  std::uint64_t manifold = 0, oriented = 0;
  std::vector<EdgeFound> first_manifold, first_oriented;  // {lower, upper}, the first few
};

// A use is `upper << 1 | (runs upper→lower)`; Use is uint32 when the vertices fit 31 bits.
template <class Use>
struct ChunkBuffers {
  std::vector<std::uint64_t> start;  // per lower vertex of the chunk, then the total
  std::vector<Use> uses;
};

// Whether the `n` ≤ 8 uses at `first` pair up as one use each way of distinct edges (a sound
// bucket), by a branch-free sorting network: most buckets are decided without a sort.
template <class Use>
bool sound_bucket(const Use* first, std::size_t n) {
  if (n % 2 != 0) return false;
  Use e[8];
  for (std::size_t k = 0; k < 8; ++k) e[k] = k < n ? first[k] : std::numeric_limits<Use>::max();
  const auto cs = [&](int i, int j) {
    const Use x = e[i], y = e[j];
    e[i] = std::min(x, y);
    e[j] = std::max(x, y);
  };
  // Batcher's odd-even merge sort of 8 (19 compare-swaps).
  cs(0, 1), cs(2, 3), cs(4, 5), cs(6, 7);
  cs(0, 2), cs(1, 3), cs(4, 6), cs(5, 7);
  cs(1, 2), cs(5, 6);
  cs(0, 4), cs(1, 5), cs(2, 6), cs(3, 7);
  cs(2, 4), cs(3, 5);
  cs(1, 2), cs(3, 4), cs(5, 6);
  bool sound = true;
  for (std::size_t k = 0; k < n; k += 2) sound &= (e[k] & 1) == 0 && e[k + 1] == e[k] + 1;
  return sound;
}

// Counts, places and checks the uses whose lower vertex is in [v0, v1), reading `blocks`.
template <class Use>
void check_chunk(const Mesh& mesh, std::uint64_t v0, std::uint64_t v1,
                 const std::vector<std::uint32_t>& blocks, std::size_t max_offenders,
                 ChunkBuffers<Use>& buf, ChunkFound& found) {
  const std::uint32_t* idx = mesh.indices.data();
  const std::size_t nt = mesh.num_triangles();
  const std::uint64_t n = v1 - v0;
  const auto each_use = [&](auto&& visit) {
    for (const std::uint32_t b : blocks) {
      const std::size_t end = std::min(nt, (std::size_t{b} + 1) * kBlockFaces);
      for (std::size_t t = std::size_t{b} * kBlockFaces; t < end; ++t) {
        const std::uint32_t f[3] = {idx[3 * t], idx[3 * t + 1], idx[3 * t + 2]};
        for (int k = 0; k < 3; ++k) {
          const std::uint32_t a = f[k], c = f[k == 2 ? 0 : k + 1];
          const std::uint32_t lo = std::min(a, c);
          if (lo - v0 < n) visit(static_cast<std::size_t>(lo - v0), std::max(a, c), a > c);
        }
      }
    }
  };
  buf.start.assign(n + 1, 0);
  each_use([&](std::size_t i, std::uint32_t, bool) { ++buf.start[i + 1]; });
  for (std::size_t i = 0; i < n; ++i) buf.start[i + 1] += buf.start[i];
  if (buf.uses.size() < buf.start[n]) buf.uses.resize(buf.start[n]);
  // Placing moves start[i] to the end of bucket i, which is where bucket i + 1 begins.
  each_use([&](std::size_t i, std::uint32_t hi, bool reversed) {
    buf.uses[buf.start[i]++] = static_cast<Use>(static_cast<Use>(hi) << 1 | (reversed ? 1 : 0));
  });

  for (std::size_t i = 0, begin = 0; i < n; begin = buf.start[i], ++i) {
    Use* first = buf.uses.data() + begin;
    Use* last = buf.uses.data() + buf.start[i];
    const auto n_uses = static_cast<std::size_t>(last - first);
    if (n_uses <= 8 && sound_bucket(first, n_uses)) continue;
    std::sort(first, last);
    const auto lo = static_cast<std::uint32_t>(v0 + i);
    for (Use* g = first; g < last;) {
      Use* h = g + 1;
      while (h < last && (*h >> 1) == (*g >> 1)) ++h;
      const auto hi = static_cast<std::uint32_t>(*g >> 1);
      if (h - g == 1) {
        found.boundary.push_back((*g & 1) ? EdgeFound{hi, lo} : EdgeFound{lo, hi});
      } else if (h - g > 2) {
        if (found.manifold++ < max_offenders) found.first_manifold.push_back({lo, hi});
      } else if (*g == *(g + 1)) {
        if (found.oriented++ < max_offenders) found.first_oriented.push_back({lo, hi});
      }
      g = h;
    }
  }
}

template <class Use>
std::vector<ChunkFound> check_all_chunks(const Mesh& mesh, std::size_t max_offenders) {
  const std::vector<BlockRange> blocks = block_ranges(mesh);
  const Chunking chunking = choose_chunking(mesh, blocks);
  // The blocks each chunk reads, in face order.
  std::vector<std::vector<std::uint32_t>> reads(chunking.chunks);
  for (std::size_t b = 0; b < blocks.size(); ++b)
    for (std::size_t k = chunking.of(blocks[b].lo_min); k <= chunking.of(blocks[b].lo_max); ++k)
      reads[k].push_back(static_cast<std::uint32_t>(b));
  std::vector<ChunkFound> found(chunking.chunks);
  tbb::enumerable_thread_specific<ChunkBuffers<Use>> buffers;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunking.chunks, 1),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      ChunkBuffers<Use>& buf = buffers.local();
                      for (std::size_t k = r.begin(); k != r.end(); ++k)
                        check_chunk(mesh, chunking.first(k), chunking.first(k + 1), reads[k],
                                    max_offenders, buf, found[k]);
                    });
  return found;
}

}  // namespace

std::vector<std::vector<std::int64_t>> faces_of_edges(
    const Mesh& mesh, const std::vector<std::pair<std::uint32_t, std::uint32_t>>& edges,
    std::size_t limit) {
  // Keys (lower << 32 | upper) sorted with their position in `edges`; a bitmap of the lower
  // vertices skips most uses without a search.
  std::vector<std::vector<std::int64_t>> faces(edges.size());
  if (edges.empty()) return faces;
  std::vector<std::pair<std::uint64_t, std::size_t>> keys;
  std::vector<bool> is_lower(mesh.num_vertices(), false);
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const auto [a, b] = edges[e];
    keys.emplace_back(std::uint64_t{std::min(a, b)} << 32 | std::max(a, b), e);
    is_lower[std::min(a, b)] = true;
  }
  std::sort(keys.begin(), keys.end());
  for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = mesh.indices[3 * t + k], b = mesh.indices[3 * t + (k + 1) % 3];
      if (!is_lower[std::min(a, b)]) continue;
      const std::uint64_t key = std::uint64_t{std::min(a, b)} << 32 | std::max(a, b);
      auto it = std::lower_bound(keys.begin(), keys.end(), std::make_pair(key, std::size_t{0}));
      for (; it != keys.end() && it->first == key; ++it)
        if (faces[it->second].size() < limit)
          faces[it->second].push_back(static_cast<std::int64_t>(t));
    }
  }
  return faces;
}

// Groups each edge's uses (chunks above) and reads closedness, manifoldness and orientation off
// them; the faces of the first offenders are found afterwards by one more pass over the faces.
EdgeResults edge_checks(const Mesh& mesh, int max_offenders) {
  const auto keep = static_cast<std::size_t>(std::max(max_offenders, 0));
  const std::vector<ChunkFound> chunks = mesh.num_vertices() <= (std::size_t{1} << 31)
                                             ? check_all_chunks<std::uint32_t>(mesh, keep)
                                             : check_all_chunks<std::uint64_t>(mesh, keep);
  EdgeResults out;
  out.closed.name = kCheckClosed;
  out.manifold.name = kCheckManifold;
  out.oriented.name = kCheckOriented;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> first_manifold, first_oriented;
  for (const ChunkFound& c : chunks) {
    for (const EdgeFound& e : c.boundary) out.boundary.emplace_back(e.from, e.to);
    out.manifold.count += c.manifold;
    out.oriented.count += c.oriented;
    for (const EdgeFound& e : c.first_manifold)
      if (first_manifold.size() < keep) first_manifold.emplace_back(e.from, e.to);
    for (const EdgeFound& e : c.first_oriented)
      if (first_oriented.size() < keep) first_oriented.emplace_back(e.from, e.to);
  }
  out.closed.count = out.boundary.size();

  // The first offenders' faces (the first 16 of an edge: an edge shared by 600,000 faces, all at
  // one point, must not make a megabyte-long message), in one pass over the faces.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> named(
      out.boundary.begin(),
      out.boundary.begin() + static_cast<std::ptrdiff_t>(std::min(keep, out.boundary.size())));
  const std::size_t n_closed = named.size();
  named.insert(named.end(), first_manifold.begin(), first_manifold.end());
  named.insert(named.end(), first_oriented.begin(), first_oriented.end());
  const std::vector<std::vector<std::int64_t>> faces = faces_of_edges(mesh, named, 16);
  for (std::size_t e = 0; e < named.size(); ++e) {
    CheckResult& c = e < n_closed                           ? out.closed
                     : e < n_closed + first_manifold.size() ? out.manifold
                                                            : out.oriented;
    c.offenders.push_back(make_offender(mesh, faces[e], {named[e].first, named[e].second}));
  }
  const auto finish = [](CheckResult& c, const std::string& what) {
    c.status = c.count == 0 ? CheckStatus::passed : CheckStatus::failed;
    c.detail = std::to_string(c.count) + " " + what;
  };
  finish(out.closed, "boundary edges (used by one face)");
  finish(out.manifold, "edges used by more than two faces");
  finish(out.oriented, "edges running the same way in both their faces");
  return out;
}

}  // namespace lightvol::detail
