#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <lightvol/core/buffer.h>
#include <lightvol/core/check.h>
#include <lightvol/light/texel.h>
#include <lightvol/volume/closing.h>
#include <lightvol/volume/static_volume.h>

namespace lightvol {

VolumeCounts static_volume_counts(LightType type, int width, int height) {
  const std::uint64_t w = static_cast<std::uint64_t>(width), h = static_cast<std::uint64_t>(height);
  const std::uint64_t grid = 2 * (w - 1) * (h - 1);
  const std::uint64_t border = 2 * (w - 1) + 2 * (h - 1);
  switch (type) {
    case LightType::spot:
      return {w * h + 1, grid + border};
    case LightType::directional:
      return {w * h + border + 1, grid + 3 * border};
    case LightType::omni:
      return {6 * w * h, 6 * grid + 12 * 2 * (w - 1) + 8};
  }
  return {};
}

std::vector<std::uint32_t> border_loop(int width, int height, bool standard) {
  LV_CHECK(width >= 2 && height >= 2);
  const auto id = [&](int col, int row) {
    return static_cast<std::uint32_t>(row) * static_cast<std::uint32_t>(width) +
           static_cast<std::uint32_t>(col);
  };
  std::vector<std::uint32_t> loop;
  loop.reserve(2 * (width - 1) + 2 * (height - 1));
  for (int c = 0; c < width - 1; ++c) loop.push_back(id(c, 0));
  for (int r = 0; r < height - 1; ++r) loop.push_back(id(width - 1, r));
  for (int c = width - 1; c > 0; --c) loop.push_back(id(c, height - 1));
  for (int r = height - 1; r > 0; --r) loop.push_back(id(0, r));
  if (!standard) std::reverse(loop.begin(), loop.end());
  return loop;
}

namespace {

// The two triangles of texel quad (col c, row r) of a W-wide grid, wound to face away from the
// light.
inline void quad_triangles(std::uint32_t r, std::uint32_t c, std::uint32_t uw, bool standard,
                           std::uint32_t* out) {
  const std::uint32_t a = r * uw + c, b = a + 1, cc = a + uw, d = cc + 1;
  if (standard) {
    out[0] = a, out[1] = b, out[2] = cc, out[3] = b, out[4] = d, out[5] = cc;
  } else {
    out[0] = a, out[1] = cc, out[2] = b, out[3] = b, out[4] = cc, out[5] = d;
  }
}

// Grid triangles of quad rows [q0, q1) (two per texel quad, wound to face away from the light)
// into `out`, 6·(W − 1) indices a row, in parallel.
void grid_quad_rows(int q0, int q1, std::uint32_t uw, bool standard, std::uint32_t* out) {
  const std::size_t per_row = 6 * (std::size_t{uw} - 1);
  tbb::parallel_for(tbb::blocked_range<int>(q0, q1), [&](const tbb::blocked_range<int>& rows) {
    for (int r = rows.begin(); r != rows.end(); ++r) {
      std::uint32_t* quad = out + static_cast<std::size_t>(r - q0) * per_row;
      for (std::uint32_t c = 0; c + 1 < uw; ++c, quad += 6)
        quad_triangles(static_cast<std::uint32_t>(r), c, uw, standard, quad);
    }
  });
}

// Grid vertices of rows [r0, r1) (one per texel, on its ray at its depth) into `out`, 3·W floats
// a row, in parallel; the Error of the first texel (in row order) whose radial depth no ray
// reaches.
Status grid_rows(const Unprojector& unproject, const DepthImage& depth, int r0, int r1, float* out,
                 const std::string& source) {
  const std::size_t uw = static_cast<std::size_t>(depth.width);
  constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
  std::atomic<std::size_t> first_bad{kNone};
  tbb::parallel_for(tbb::blocked_range<int>(r0, r1), [&](const tbb::blocked_range<int>& rows) {
    for (int r = rows.begin(); r != rows.end(); ++r) {
      const std::size_t row_start = static_cast<std::size_t>(r) * uw;
      const int bad_col = unproject.row_points(r, &depth.values[row_start],
                                               out + 3 * static_cast<std::size_t>(r - r0) * uw);
      if (bad_col < 0) continue;
      const std::size_t v = row_start + static_cast<std::size_t>(bad_col);
      std::size_t seen = first_bad.load();
      while (v < seen && !first_bad.compare_exchange_weak(seen, v)) {
      }
    }
  });
  const std::size_t bad = first_bad.load();
  if (bad == kNone) return {};
  return unreachable_radial_depth(source, static_cast<int>(bad % uw), static_cast<int>(bad / uw),
                                  depth.values[bad]);
}

// The grid's border loop as the closing's ring.
std::vector<BorderVertex> closing_ring(int width, int height, bool standard) {
  const auto uw = static_cast<std::uint32_t>(width);
  std::vector<BorderVertex> ring;
  for (const std::uint32_t v : border_loop(width, height, standard))
    ring.push_back({v, static_cast<int>(v % uw), static_cast<int>(v / uw)});
  return ring;
}

// What check_representable decides from: gathered vertex by vertex and face by face, so a
// streamed volume is judged by the same numbers as a held one.
struct RepresentableTally {
  bool finite = true;
  double largest = 0;
  Vec3d lo{std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
           std::numeric_limits<double>::max()};
  Vec3d hi{-std::numeric_limits<double>::max(), -std::numeric_limits<double>::max(),
           -std::numeric_limits<double>::max()};
  std::uint64_t vertices = 0, triangles = 0, collapsed = 0;

  void add_vertex(const float* q) {
    ++vertices;
    const Vec3d p{q[0], q[1], q[2]};
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      finite = false;
      return;
    }
    largest = std::max({largest, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  void add_triangle(const float* qa, const float* qb, const float* qc) {
    ++triangles;
    const Vec3d a{qa[0], qa[1], qa[2]}, b{qb[0], qb[1], qb[2]}, c{qc[0], qc[1], qc[2]};
    const Vec3d n = cross(b - a, c - a);
    if (n.x == 0 && n.y == 0 && n.z == 0) ++collapsed;
  }
  void merge(const RepresentableTally& o) {
    finite = finite && o.finite;
    largest = std::max(largest, o.largest);
    lo = {std::min(lo.x, o.lo.x), std::min(lo.y, o.lo.y), std::min(lo.z, o.lo.z)};
    hi = {std::max(hi.x, o.hi.x), std::max(hi.y, o.hi.y), std::max(hi.z, o.hi.z)};
    vertices += o.vertices;
    triangles += o.triangles;
    collapsed += o.collapsed;
  }
};

Status representable_verdict(const RepresentableTally& tally, const Light& light, Space space,
                             const std::string& light_source);

}  // namespace

Result<Mesh> build_static_volume(const Light& light, const DepthImage& depth,
                                 const VolumeOptions& options, const std::string& source) {
  LV_CHECK(light.type != LightType::omni);
  const int w = depth.width, h = depth.height;
  LV_CHECK(w >= 2 && h >= 2);
  const Unprojector unproject(light, w, h, 0, options.space);
  const VolumeCounts counts = static_volume_counts(light.type, w, h);
  LV_CHECK_LT(counts.vertices, std::uint64_t{std::numeric_limits<std::uint32_t>::max()});

  Mesh mesh;
  const std::size_t grid_vertices = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  reserve_large(mesh.positions, 3 * counts.vertices);
  reserve_large(mesh.indices, 3 * counts.triangles);
  mesh.positions.resize(3 * grid_vertices);
  mesh.indices.resize(6 * static_cast<std::size_t>(w - 1) * static_cast<std::size_t>(h - 1));

  if (Status s = grid_rows(unproject, depth, 0, h, mesh.positions.data(), source); !s)
    return s.error();
  const bool standard = unproject.standard_winding();
  grid_quad_rows(0, h - 1, static_cast<std::uint32_t>(w), standard, mesh.indices.data());
  // Closing: fan to the apex (spot) or walls and a cap on the near plane (directional).
  append_closing(light.type, unproject, w, h, closing_ring(w, h, standard), &mesh);
  LV_CHECK_EQ(mesh.num_vertices(), counts.vertices);
  LV_CHECK_EQ(mesh.num_triangles(), counts.triangles);
  return mesh;
}

Status check_representable(const Mesh& mesh, const Light& light, Space space,
                           const std::string& light_source) {
  RepresentableTally tally;
  for (std::size_t v = 0; v < mesh.num_vertices(); ++v) tally.add_vertex(&mesh.positions[3 * v]);
  for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
    const auto tri = mesh.triangle(t);
    tally.add_triangle(&mesh.positions[3 * std::size_t{tri[0]}],
                       &mesh.positions[3 * std::size_t{tri[1]}],
                       &mesh.positions[3 * std::size_t{tri[2]}]);
  }
  return representable_verdict(tally, light, space, light_source);
}

namespace {

Status representable_verdict(const RepresentableTally& tally, const Light& light, Space space,
                             const std::string& light_source) {
  constexpr double kLargest = 1e18;  // squares stay below float's 3.4e38
  const auto shown = [](double x) {
    std::ostringstream out;
    out << x;
    return out.str();
  };
  const std::string frustum_keys =
      light.type == LightType::spot   ? "keys 'near', 'far' and 'fov_y_deg'"
      : light.type == LightType::omni ? "keys 'near' and 'far'"
                                      : "keys 'ortho', 'near' and 'far'";
  const double largest = tally.largest;
  const Vec3d lo = tally.lo, hi = tally.hi;
  if (!tally.finite)
    return Error{light_source + ": " + frustum_keys +
                 ": the volume's vertices are not finite numbers (near " + shown(light.near) +
                 ", far " + shown(light.far) +
                 ": more than double precision holds); bring far closer to near"};
  if (largest > kLargest)
    return Error{light_source + ": " + frustum_keys + ": the volume reaches coordinate " +
                 shown(largest) + "; float32 meshes need coordinates below " + shown(kLargest) +
                 " (choose the scene's units so that the frustum is smaller)"};
  const Vec3d span = hi - lo;
  const double across = std::max({span.x, span.y, span.z});
  // The checks form areas and volumes in float: a volume smaller than this underflows them.
  constexpr double kSmallest = 1e-12;
  if (across < kSmallest)
    return Error{light_source + ": " + frustum_keys + ": the volume is " + shown(across) +
                 " across; float32 meshes and their checks need at least " + shown(kSmallest) +
                 " (choose the scene's units, or near and far, so that it is larger)"};
  const std::uint64_t collapsed = tally.collapsed;
  // Float32 steps at the volume's coordinates against the spacing of its vertices (its thinnest
  // extent over the square root of their count, a texel's spacing across a grid): steps coarser
  // than a sixteenth of it move vertices by more than the checks allow for, which then refuse the
  // volume (a spot far from the origin, or a fov of 1e-6 degrees).
  const double thinnest = std::min({span.x, span.y, span.z});
  const double spacing = thinnest / std::sqrt(std::max<double>(1, double(tally.vertices)));
  const bool coarse = largest * std::numeric_limits<float>::epsilon() > spacing / 16;
  if (collapsed == 0 && !coarse) return {};
  const Vec3d extent = hi - lo;
  const double size = std::max({extent.x, extent.y, extent.z});
  const double step = largest * std::numeric_limits<float>::epsilon();
  std::string what = light_source + ": float32 cannot hold this volume (coordinates up to " +
                     shown(largest) + ", steps of " + shown(step) + ", vertices about " +
                     shown(spacing) + " apart; " + std::to_string(collapsed) + " of " +
                     std::to_string(tally.triangles) + " faces collapse to zero area)";

  if (space == Space::world && largest > 100 * size)
    return Error{what + ": key 'position': the light is far from the origin for the volume's " +
                 "size " + shown(size) +
                 "; write it in the light's eye space with --space light and place it with the "
                 "light's view matrix"};
  return Error{what + ": " + frustum_keys +
               ": the frustum is too thin, or far/near too large, for float32; widen it or bring "
               "near and far closer"};
}

}  // namespace

struct StaticVolumeStream::State {
  const Light& light;
  const DepthImage& depth;
  Unprojector unproject;
  std::string source, light_source;
  Space space;
  VolumeCounts counts;
  ClosingPart closing;  // made by positions()
};

StaticVolumeStream::StaticVolumeStream(const Light& light, const DepthImage& depth,
                                       const VolumeOptions& options, std::string source,
                                       std::string light_source) {
  LV_CHECK(light.type != LightType::omni);
  LV_CHECK(depth.width >= 2 && depth.height >= 2);
  state_.reset(new State{light,
                         depth,
                         Unprojector(light, depth.width, depth.height, 0, options.space),
                         std::move(source),
                         std::move(light_source),
                         options.space,
                         static_volume_counts(light.type, depth.width, depth.height),
                         {}});
  LV_CHECK_LT(state_->counts.vertices, std::uint64_t{std::numeric_limits<std::uint32_t>::max()});
}

StaticVolumeStream::~StaticVolumeStream() = default;

std::uint64_t StaticVolumeStream::num_vertices() const { return state_->counts.vertices; }
std::uint64_t StaticVolumeStream::num_triangles() const { return state_->counts.triangles; }

// Long (over 80 lines) on purpose: one pass over blocks of rows makes each block's vertices, hands
// them on, and folds them and the grid triangles they complete (with the row before) into the
// tallies; the border rows and columns are kept for the closing.
Status StaticVolumeStream::positions(const PositionSink& sink) {
  State& st = *state_;
  const int w = st.depth.width, h = st.depth.height;
  const std::size_t uw = static_cast<std::size_t>(w);
  const bool standard = st.unproject.standard_winding();
  const std::size_t grid_vertices = uw * static_cast<std::size_t>(h);
  const std::size_t quad_triangles_per_row = 2 * (uw - 1);
  const int block_rows = std::clamp(static_cast<int>((std::size_t{1} << 18) / uw), 1, h);
  std::vector<float> buffer(3 * uw * (static_cast<std::size_t>(block_rows) + 1));
  // The border: rows 0 and H−1, columns 0 and W−1 (for the closing's triangles).
  std::vector<float> top(3 * uw), bottom(3 * uw), left(3 * static_cast<std::size_t>(h)),
      right(3 * static_cast<std::size_t>(h));
  RepresentableTally tally;
  SignedVolumeSum volume(st.counts.triangles);
  bool have_previous = false;
  for (int r0 = 0; r0 < h; r0 += block_rows) {
    const int r1 = std::min(h, r0 + block_rows);
    const int first_row = have_previous ? r0 - 1 : r0;  // the buffer's first row
    float* fresh = buffer.data() + (have_previous ? 3 * uw : 0);
    if (Status s = grid_rows(st.unproject, st.depth, r0, r1, fresh, st.source); !s) return s;
    // Then (every row of the block made) the tallies of its vertices and of the quad rows ending
    // in it.
    const RepresentableTally block = tbb::parallel_reduce(
        tbb::blocked_range<int>(r0, r1), RepresentableTally{},
        [&](const tbb::blocked_range<int>& rows, RepresentableTally acc) {
          for (int r = rows.begin(); r != rows.end(); ++r) {
            const float* out = fresh + 3 * static_cast<std::size_t>(r - r0) * uw;
            for (std::size_t c = 0; c < uw; ++c) acc.add_vertex(out + 3 * c);
            // Quad row r − 1 (rows r − 1 and r), when row r − 1 is in the buffer.
            if (r == 0) continue;
            const float* above = out - 3 * uw;
            std::uint32_t tri[6];
            for (std::size_t c = 0; c + 1 < uw; ++c) {
              quad_triangles(0, static_cast<std::uint32_t>(c), static_cast<std::uint32_t>(uw),
                             standard, tri);  // rows 0 (above) and 1 (out)
              const auto at = [&](std::uint32_t v) {
                return (v >= uw ? out + 3 * (v - uw) : above + 3 * std::size_t{v});
              };
              acc.add_triangle(at(tri[0]), at(tri[1]), at(tri[2]));
              acc.add_triangle(at(tri[3]), at(tri[4]), at(tri[5]));
            }
          }
          return acc;
        },
        [](RepresentableTally a, const RepresentableTally& b) {
          a.merge(b);
          return a;
        });
    tally.merge(block);
    if (!sink(fresh, static_cast<std::size_t>(r1 - r0) * uw)) return {};
    // The volume's sum takes the grid triangles in order: quad rows [first_row, r1 − 1).
    const auto row_of = [&](std::size_t v) {
      return buffer.data() + 3 * (v - static_cast<std::size_t>(first_row) * uw);
    };
    const std::size_t t_begin = static_cast<std::size_t>(first_row) * quad_triangles_per_row;
    const std::size_t t_end = static_cast<std::size_t>(r1 - 1) * quad_triangles_per_row;
    volume.add(t_begin, t_end - t_begin, [&](std::size_t t, int k) {
      const std::size_t q = t / quad_triangles_per_row, c = (t % quad_triangles_per_row) / 2;
      std::uint32_t tri[6];
      quad_triangles(static_cast<std::uint32_t>(q), static_cast<std::uint32_t>(c),
                     static_cast<std::uint32_t>(uw), standard, tri);
      return row_of(tri[3 * (t % 2) + static_cast<std::size_t>(k)]);
    });
    for (int r = r0; r < r1; ++r) {
      const float* row = fresh + 3 * static_cast<std::size_t>(r - r0) * uw;
      if (r == 0) std::copy(row, row + 3 * uw, top.begin());
      if (r == h - 1) std::copy(row, row + 3 * uw, bottom.begin());
      std::copy(row, row + 3, left.begin() + 3 * r);
      std::copy(row + 3 * (uw - 1), row + 3 * uw, right.begin() + 3 * r);
    }
    // Keep the last row for the next block's first quad row.
    std::copy(fresh + 3 * static_cast<std::size_t>(r1 - 1 - r0) * uw,
              fresh + 3 * static_cast<std::size_t>(r1 - r0) * uw, buffer.begin());
    have_previous = true;
  }

  // The closing: its vertices after the grid's, its triangles after the grid's.
  st.closing = make_closing(st.light.type, st.unproject, w, h, closing_ring(w, h, standard),
                            static_cast<std::uint32_t>(grid_vertices));
  const std::size_t closing_vertices = st.closing.positions.size() / 3;
  for (std::size_t v = 0; v < closing_vertices; ++v) tally.add_vertex(&st.closing.positions[3 * v]);
  if (!sink(st.closing.positions.data(), closing_vertices)) return {};
  const auto position = [&](std::uint32_t v) -> const float* {
    if (v >= grid_vertices) return &st.closing.positions[3 * (v - grid_vertices)];
    const std::size_t col = v % uw, row = v / uw;
    if (row == 0) return &top[3 * col];
    if (row + 1 == static_cast<std::size_t>(h)) return &bottom[3 * col];
    return col == 0 ? &left[3 * row] : &right[3 * row];
  };
  const std::vector<std::uint32_t>& ci = st.closing.indices;
  for (std::size_t i = 0; i < ci.size(); i += 3)
    tally.add_triangle(position(ci[i]), position(ci[i + 1]), position(ci[i + 2]));
  const std::size_t grid_triangles = static_cast<std::size_t>(h - 1) * quad_triangles_per_row;
  volume.add(grid_triangles, ci.size() / 3,
             [&](std::size_t t, int k) { return position(ci[3 * (t - grid_triangles) + k]); });
  LV_CHECK_EQ(tally.vertices, st.counts.vertices);
  LV_CHECK_EQ(tally.triangles, st.counts.triangles);
  if (Status s = representable_verdict(tally, st.light, st.space, st.light_source); !s) return s;
  for (int k = 0; k < 3; ++k) {
    bounds_.min[k] = k == 0 ? tally.lo.x : k == 1 ? tally.lo.y : tally.lo.z;
    bounds_.max[k] = k == 0 ? tally.hi.x : k == 1 ? tally.hi.y : tally.hi.z;
  }
  volume_ = volume.volume();
  return {};
}

Status StaticVolumeStream::triangles(const TriangleSink& sink) {
  const State& st = *state_;
  const int w = st.depth.width, h = st.depth.height;
  const std::uint32_t uw = static_cast<std::uint32_t>(w);
  const bool standard = st.unproject.standard_winding();
  const std::size_t per_row = 6 * (static_cast<std::size_t>(w) - 1);
  const int block_rows = std::clamp(static_cast<int>((std::size_t{1} << 18) / uw), 1, h);
  std::vector<std::uint32_t> buffer(per_row * static_cast<std::size_t>(block_rows));
  for (int q0 = 0; q0 < h - 1; q0 += block_rows) {
    const int q1 = std::min(h - 1, q0 + block_rows);
    grid_quad_rows(q0, q1, uw, standard, buffer.data());
    if (!sink(buffer.data(), static_cast<std::size_t>(q1 - q0) * per_row / 3)) return {};
  }
  sink(st.closing.indices.data(), st.closing.indices.size() / 3);
  return {};
}

}  // namespace lightvol
