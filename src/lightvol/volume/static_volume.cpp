#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <initializer_list>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include <lightvol/core/buffer.h>
#include <lightvol/core/check.h>
#include <lightvol/light/texel.h>
#include <lightvol/volume/closing.h>
#include <lightvol/volume/detail/float32_guard.h>
#include <lightvol/volume/float32_guard.h>
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

// The float32 guard's passes (volume/detail/float32_guard.h), which the stream runs on its rows.
using detail::FaceFinding;
using detail::FaceJudge;
using detail::FaceTally;
using detail::guard_light;
using detail::GuardLight;
using detail::judge_face;
using detail::representable_verdict;
using detail::tally_vertices;
using detail::vertex_verdict;
using detail::VertexTally;

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

// The corners of column 0's quad in a quad row whose upper grid row starts at `above` (the lower
// row right after it): corner k of triangle i of column c's quad is corner[3i + k] + 3c.
void quad_corners(const float* above, std::uint32_t uw, bool standard, const float* (&corner)[6]) {
  std::uint32_t tri[6];
  quad_triangles(0, 0, uw, standard, tri);
  for (int k = 0; k < 6; ++k) corner[k] = above + 3 * std::size_t{tri[k]};
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

// An empty mesh with room for `counts`, its pages mapped: in this thread alone (populate), or by
// all cores (populate_in_parallel).
Mesh reserved_mesh(const VolumeCounts& counts, bool in_parallel) {
  Mesh mesh;
  mesh.positions.reserve(3 * counts.vertices);
  mesh.indices.reserve(3 * counts.triangles);
  const std::initializer_list<std::pair<const void*, std::size_t>> pages = {
      {mesh.positions.data(), 3 * counts.vertices * sizeof(float)},
      {mesh.indices.data(), 3 * counts.triangles * sizeof(std::uint32_t)}};
  if (in_parallel) {
    populate_in_parallel(pages);
  } else {
    populate(pages);
  }
  return mesh;
}

}  // namespace

Mesh reserve_static_volume(LightType type, int width, int height) {
  LV_CHECK(type != LightType::omni);
  LV_CHECK(width >= 2 && height >= 2);
  return reserved_mesh(static_volume_counts(type, width, height), false);
}

Result<Mesh> detail::assemble_static_volume(const Light& light, const DepthImage& depth,
                                            const VolumeOptions& options, const std::string& source,
                                            Mesh storage) {
  LV_CHECK(light.type != LightType::omni);
  const int w = depth.width, h = depth.height;
  LV_CHECK(w >= 2 && h >= 2);
  const Unprojector unproject(light, w, h, 0, options.space);
  const VolumeCounts counts = static_volume_counts(light.type, w, h);
  LV_CHECK_LT(counts.vertices, std::uint64_t{std::numeric_limits<std::uint32_t>::max()});

  const std::size_t grid_vertices = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  // Pages mapped first (the kernel zeroes each as it maps it, the slowest part of the build
  // on a virtual machine): by reserve_static_volume while the map was read, else here in parallel
  // blocks; then zeroed again by the vectors.
  Mesh mesh;
  if (storage.positions.capacity() >= 3 * counts.vertices &&
      storage.indices.capacity() >= 3 * counts.triangles) {
    mesh = std::move(storage);
    mesh.positions.clear();
    mesh.indices.clear();
  } else {
    storage = Mesh{};
    mesh = reserved_mesh(counts, true);
  }
  tbb::parallel_invoke(
      [&] { mesh.positions.resize(3 * grid_vertices); },
      [&] {
        mesh.indices.resize(6 * static_cast<std::size_t>(w - 1) * static_cast<std::size_t>(h - 1));
      });

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

Result<Mesh> build_static_volume(const Light& light, const DepthImage& depth,
                                 const VolumeOptions& options, const std::string& source,
                                 Mesh storage) {
  Result<Mesh> mesh =
      detail::assemble_static_volume(light, depth, options, source, std::move(storage));
  if (!mesh) return mesh;
  if (Status s = check_representable(*mesh, light, options.space, options.light_source); !s)
    return s.error();
  return mesh;
}

std::vector<std::uint32_t> static_volume_indices(const Light& light, int width, int height) {
  LV_CHECK(light.type != LightType::omni);
  LV_CHECK(width >= 2 && height >= 2);
  const Unprojector unproject(light, width, height, 0, Space::world);
  const VolumeCounts counts = static_volume_counts(light.type, width, height);
  LV_CHECK_LT(counts.vertices, std::uint64_t{std::numeric_limits<std::uint32_t>::max()});
  const bool standard = unproject.standard_winding();
  std::vector<std::uint32_t> indices(6 * static_cast<std::size_t>(width - 1) *
                                     static_cast<std::size_t>(height - 1));
  grid_quad_rows(0, height - 1, static_cast<std::uint32_t>(width), standard, indices.data());
  const ClosingPart closing =
      make_closing(light.type, unproject, width, height, closing_ring(width, height, standard),
                   static_cast<std::uint32_t>(width) * static_cast<std::uint32_t>(height));
  indices.insert(indices.end(), closing.indices.begin(), closing.indices.end());
  LV_CHECK_EQ(indices.size(), 3 * counts.triangles);
  return indices;
}

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

// Long (over 80 lines) on purpose: two passes over blocks of rows. The first makes each block's
// vertices and tallies them for the float32 guard (its faces' tolerance needs the largest
// coordinate, known only after every vertex); the second makes them again, hands them on, judges
// the grid triangles they complete (with the row before) and sums the volume; the border rows and
// columns are kept for the closing.
Status StaticVolumeStream::positions(const PositionSink& sink) {
  State& st = *state_;
  const int w = st.depth.width, h = st.depth.height;
  const std::size_t uw = static_cast<std::size_t>(w);
  const bool standard = st.unproject.standard_winding();
  const std::size_t grid_vertices = uw * static_cast<std::size_t>(h);
  const std::size_t quad_triangles_per_row = 2 * (uw - 1);
  const int block_rows = std::clamp(static_cast<int>((std::size_t{1} << 18) / uw), 1, h);
  std::vector<float> buffer(3 * uw * (static_cast<std::size_t>(block_rows) + 1));
  const GuardLight guard = guard_light(st.light, st.space);
  // The closing: its vertices after the grid's, its triangles after the grid's (it needs none of
  // the grid's positions).
  st.closing = make_closing(st.light.type, st.unproject, w, h, closing_ring(w, h, standard),
                            static_cast<std::uint32_t>(grid_vertices));
  const std::size_t closing_vertices = st.closing.positions.size() / 3;

  // First pass: the vertices' tally; each block's rows made and dropped.
  VertexTally vertices;
  for (int r0 = 0; r0 < h; r0 += block_rows) {
    const int r1 = std::min(h, r0 + block_rows);
    if (Status s = grid_rows(st.unproject, st.depth, r0, r1, buffer.data(), st.source); !s)
      return s;
    vertices.merge(tally_vertices(buffer.data(), static_cast<std::size_t>(r1 - r0) * uw, guard));
  }
  vertices.merge(tally_vertices(st.closing.positions.data(), closing_vertices, guard));
  LV_CHECK_EQ(vertices.vertices, st.counts.vertices);
  if (Status s = vertex_verdict(vertices, st.light, st.light_source); !s) return s;
  const FaceJudge judge(vertices, guard);

  // Second pass: the same rows, handed on, their faces judged and summed.
  // The border: rows 0 and H−1, columns 0 and W−1 (for the closing's triangles).
  std::vector<float> top(3 * uw), bottom(3 * uw), left(3 * static_cast<std::size_t>(h)),
      right(3 * static_cast<std::size_t>(h));
  FaceTally faces;
  SignedVolumeSum volume(st.counts.triangles);
  bool have_previous = false;
  for (int r0 = 0; r0 < h; r0 += block_rows) {
    const int r1 = std::min(h, r0 + block_rows);
    const int first_row = have_previous ? r0 - 1 : r0;  // the buffer's first row
    float* fresh = buffer.data() + (have_previous ? 3 * uw : 0);
    if (Status s = grid_rows(st.unproject, st.depth, r0, r1, fresh, st.source); !s) return s;
    // Then (every row of the block made) the tally of the quad rows ending in it: quad row r − 1
    // (rows r − 1 and r) for each row r of the block but row 0.
    const FaceTally block = tbb::parallel_reduce(
        tbb::blocked_range<int>(std::max(r0, 1), r1), FaceTally{},
        [&](const tbb::blocked_range<int>& rows, FaceTally acc) {
          for (int r = rows.begin(); r != rows.end(); ++r) {
            const float* corner[6];
            quad_corners(fresh + 3 * (static_cast<std::size_t>(r - r0) - 1) * uw,
                         static_cast<std::uint32_t>(uw), standard, corner);
            std::uint64_t collapsed = 0, turned = 0;
            for (std::size_t c = 0; c + 1 < uw; ++c) {
              const std::size_t o = 3 * c;
              for (int i = 0; i < 2; ++i) {
                const FaceFinding found = judge_face(corner[3 * i] + o, corner[3 * i + 1] + o,
                                                     corner[3 * i + 2] + o, judge);
                collapsed += found == FaceFinding::collapsed;
                turned += found == FaceFinding::turned;
              }
            }
            acc.triangles += 2 * (uw - 1), acc.collapsed += collapsed, acc.turned += turned;
          }
          return acc;
        },
        [](FaceTally a, const FaceTally& b) {
          a.merge(b);
          return a;
        });
    faces.merge(block);
    if (!sink(fresh, static_cast<std::size_t>(r1 - r0) * uw)) return {};
    // The volume's sum takes the grid triangles in order: quad rows [first_row, r1 − 1), whose
    // upper rows begin the buffer.
    const std::size_t t_begin = static_cast<std::size_t>(first_row) * quad_triangles_per_row;
    const std::size_t t_end = static_cast<std::size_t>(r1 - 1) * quad_triangles_per_row;
    // Quad row by quad row, with the tally's corners.
    volume.add_runs(t_begin, t_end - t_begin, [&](std::size_t t0, std::size_t t1, double acc) {
      for (std::size_t t = t0; t != t1;) {
        const std::size_t q = t / quad_triangles_per_row;
        const float* corner[6];
        quad_corners(buffer.data() + 3 * (q - static_cast<std::size_t>(first_row)) * uw,
                     static_cast<std::uint32_t>(uw), standard, corner);
        for (std::size_t k = t - q * quad_triangles_per_row; k < quad_triangles_per_row && t != t1;
             ++k, ++t) {
          const std::size_t o = 3 * (k / 2), i = 3 * (k % 2);
          acc += volume_det(corner[i] + o, corner[i + 1] + o, corner[i + 2] + o);
        }
      }
      return acc;
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

  if (!sink(st.closing.positions.data(), closing_vertices)) return {};
  const auto position = [&](std::uint32_t v) -> const float* {
    if (v >= grid_vertices) return &st.closing.positions[3 * (v - grid_vertices)];
    const std::size_t col = v % uw, row = v / uw;
    if (row == 0) return &top[3 * col];
    if (row + 1 == static_cast<std::size_t>(h)) return &bottom[3 * col];
    return col == 0 ? &left[3 * row] : &right[3 * row];
  };
  const std::vector<std::uint32_t>& ci = st.closing.indices;
  faces.add(
      ci.size() / 3, [&](std::size_t t, int k) { return position(ci[3 * t + k]); }, judge);
  const std::size_t grid_triangles = static_cast<std::size_t>(h - 1) * quad_triangles_per_row;
  volume.add(grid_triangles, ci.size() / 3,
             [&](std::size_t t, int k) { return position(ci[3 * (t - grid_triangles) + k]); });
  LV_CHECK_EQ(faces.triangles, st.counts.triangles);
  if (Status s = representable_verdict(vertices, faces, st.light, st.space, st.light_source); !s)
    return s;
  for (int k = 0; k < 3; ++k) {
    bounds_.min[k] = vertices.lo[k];
    bounds_.max[k] = vertices.hi[k];
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
