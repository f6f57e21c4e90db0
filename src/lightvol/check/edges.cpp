// Closed, edge-manifold, oriented: one linear pass over the edges (a counting sort by the lower
// vertex, then a sort of each small bucket).
#include <algorithm>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <lightvol/check/detail/linear_checks.h>

namespace lightvol::detail {
namespace {

// One use of an undirected edge {lo, hi} by face `face`, running lo→hi (forward) or hi→lo.
struct EdgeUse {
  std::uint64_t edge;      // lo << 32 | hi
  std::uint32_t face_dir;  // face << 1 | (runs hi→lo)
  bool operator<(const EdgeUse& o) const {
    return edge != o.edge ? edge < o.edge : face_dir < o.face_dir;
  }
};

}  // namespace

// Buckets every edge use by its lower vertex (a counting sort, linear), sorts each small bucket,
// and reads closedness, manifoldness and orientation off the groups of equal edges.
EdgeResults edge_checks(const Mesh& mesh, int max_offenders) {
  const std::size_t nt = mesh.num_triangles(), nv = mesh.num_vertices();
  const auto use_of = [&](std::size_t t, int k) {
    const std::uint64_t a = mesh.indices[3 * t + k];
    const std::uint64_t b = mesh.indices[3 * t + (k + 1) % 3];
    return EdgeUse{std::min(a, b) << 32 | std::max(a, b),
                   static_cast<std::uint32_t>(t << 1 | (a > b ? 1 : 0))};
  };
  std::vector<std::uint32_t> start(nv + 1, 0);
  for (std::size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k)
      ++start[std::min(mesh.indices[3 * t + k], mesh.indices[3 * t + (k + 1) % 3]) + 1];
  for (std::size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
  std::vector<EdgeUse> uses(3 * nt);
  {
    std::vector<std::uint32_t> next(start.begin(), start.end() - 1);
    for (std::size_t t = 0; t < nt; ++t)
      for (int k = 0; k < 3; ++k) {
        const EdgeUse u = use_of(t, k);
        uses[next[u.edge >> 32]++] = u;
      }
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 1 << 12),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t v = r.begin(); v != r.end(); ++v)
                        std::sort(uses.begin() + start[v], uses.begin() + start[v + 1]);
                    });

  EdgeResults out;
  out.closed.name = kCheckClosed;
  out.manifold.name = kCheckManifold;
  out.oriented.name = kCheckOriented;
  const auto lo_of = [](std::uint64_t e) { return static_cast<std::uint32_t>(e >> 32); };
  const auto hi_of = [](std::uint64_t e) { return static_cast<std::uint32_t>(e & 0xffffffffu); };
  // The first 16 faces of an edge: an edge shared by 600,000 faces (all at one point) must not
  // make a megabyte-long message.
  const auto faces_of = [&](std::size_t i, std::size_t j) {
    std::vector<std::int64_t> faces;
    for (std::size_t k = i; k < j && k < i + 16; ++k) faces.push_back(uses[k].face_dir >> 1);
    return faces;
  };
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i + 1;
    while (j < uses.size() && uses[j].edge == uses[i].edge) ++j;
    const std::uint64_t e = uses[i].edge;
    const std::size_t n = j - i;
    if (n == 1) {
      const bool reversed = uses[i].face_dir & 1;
      const std::uint32_t from = reversed ? hi_of(e) : lo_of(e),
                          to = reversed ? lo_of(e) : hi_of(e);
      out.boundary.emplace_back(from, to);
      out.boundary_faces.push_back(uses[i].face_dir >> 1);
      if (out.closed.count++ < static_cast<std::uint64_t>(max_offenders))
        out.closed.offenders.push_back(make_offender(mesh, faces_of(i, j), {from, to}));
    } else if (n > 2) {
      if (out.manifold.count++ < static_cast<std::uint64_t>(max_offenders))
        out.manifold.offenders.push_back(make_offender(mesh, faces_of(i, j), {lo_of(e), hi_of(e)}));
    } else if ((uses[i].face_dir & 1) == (uses[i + 1].face_dir & 1)) {
      if (out.oriented.count++ < static_cast<std::uint64_t>(max_offenders))
        out.oriented.offenders.push_back(make_offender(mesh, faces_of(i, j), {lo_of(e), hi_of(e)}));
    }
    i = j;
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
