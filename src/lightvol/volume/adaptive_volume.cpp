#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <lightvol/core/check.h>
#include <lightvol/core/limits.h>
#include <lightvol/light/texel.h>
#include <lightvol/tessellate/collapse_grid.h>
#include <lightvol/volume/adaptive_volume.h>
#include <lightvol/volume/closing.h>
#include <lightvol/volume/float32_guard.h>

namespace lightvol {

namespace {

std::size_t ring_size(const AdaptiveGrid& grid) {
  std::size_t n = 0;
  for (const std::vector<int>& side : grid.border) n += side.size() - 1;
  return n;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

VolumeCounts adaptive_volume_counts(LightType type, const AdaptiveGrid& grid) {
  const ClosingCounts closing = closing_counts(type, ring_size(grid));
  return {grid.vertices.size() + closing.vertices, grid.num_triangles() + closing.triangles};
}

Result<Mesh> assemble_adaptive_volume(const Light& light, const DepthImage& depth,
                                      const AdaptiveGrid& grid, const VolumeOptions& options,
                                      const std::string& source) {
  LV_CHECK(light.type != LightType::omni);
  LV_CHECK(grid.width == depth.width && grid.height == depth.height);
  const int w = depth.width, h = depth.height;
  const Unprojector unproject(light, w, h, 0, options.space);
  const VolumeCounts counts = adaptive_volume_counts(light.type, grid);
  LV_CHECK_LT(counts.vertices, std::uint64_t{std::numeric_limits<std::uint32_t>::max()});

  Mesh mesh;
  const std::size_t nv = grid.vertices.size();
  mesh.positions.resize(3 * nv);
  std::atomic<std::size_t> first_bad{std::numeric_limits<std::size_t>::max()};
  const std::uint32_t uw = static_cast<std::uint32_t>(w);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 4096),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t v = range.begin(); v != range.end(); ++v) {
                        const std::uint32_t id = grid.vertices[v];
                        const int c = static_cast<int>(id % uw), r = static_cast<int>(id / uw);
                        Vec3d p;
                        if (!unproject.point(c, r, depth.values[id], &p)) {
                          std::size_t seen = first_bad.load();
                          while (id < seen && !first_bad.compare_exchange_weak(seen, id)) {
                          }
                          p = unproject.near_point(c, r);
                        }
                        mesh.positions[3 * v] = static_cast<float>(p.x);
                        mesh.positions[3 * v + 1] = static_cast<float>(p.y);
                        mesh.positions[3 * v + 2] = static_cast<float>(p.z);
                      }
                    });
  if (const std::size_t bad = first_bad.load(); bad != std::numeric_limits<std::size_t>::max()) {
    return unreachable_radial_depth(source, static_cast<int>(bad % w), static_cast<int>(bad / w),
                                    depth.values[bad]);
  }
  mesh.indices.reserve(3 * counts.triangles);
  mesh.indices.insert(mesh.indices.end(), grid.indices.begin(), grid.indices.end());

  const std::vector<BorderVertex> ring =
      border_ring(w, h, grid.border, unproject.standard_winding(),
                  [&](int col, int row) { return grid.vertex_index(col, row); });
  append_closing(light.type, unproject, w, h, ring, &mesh);
  LV_CHECK_EQ(mesh.num_vertices(), counts.vertices);
  LV_CHECK_EQ(mesh.num_triangles(), counts.triangles);
  return mesh;
}

Result<double> adaptive_bound(const AdaptiveOptions& options) {
  const bool error = options.refinement == Refinement::max_error;
  const double bound = error ? options.max_error : options.threshold;
  if (!std::isfinite(bound) || bound < 0) {
    std::ostringstream shown;
    shown << bound;
    return Error{std::string(error ? "max_error" : "threshold") +
                 ": expected a finite number >= 0, got " + shown.str()};
  }
  return bound;
}

Result<Mesh> build_adaptive_volume(const Light& light, const DepthImage& depth,
                                   const VolumeOptions& volume, const AdaptiveOptions& options,
                                   const std::string& source, AdaptiveReport* report) {
  LV_CHECK(light.type != LightType::omni);
  const Result<double> bound = adaptive_bound(options);
  if (!bound) return bound.error();
  const auto start = std::chrono::steady_clock::now();
  // `depth` outlives the pyramid: its floats can serve as the texels' depths.
  Result<TexelDepths> texels = TexelDepths::create(light, depth, 0, source, true);
  if (!texels) return texels.error();
  // One bound: the pyramid is capped there (cells it splits anyway are not measured).
  const RefinementPyramid pyramid(std::move(*texels), options.refinement, *bound);
  AdaptiveReport r;
  r.pyramid_seconds = seconds_since(start);

  const bool standard =
      Unprojector(light, depth.width, depth.height, 0, volume.space).standard_winding();
  const bool collapse =
      options.refinement == Refinement::max_error && options.tessellation == Tessellation::collapse;
  // What grows with the tessellation (the quadtree's triangles, the collapse's tables, the volume)
  // is measured against the budget once the leaves are counted, before any of it is allocated.
  Status room;
  AdaptiveGrid grid = pyramid.tessellate(*bound, standard, {}, [&](std::uint64_t triangles) {
    room = check_memory(adaptive_memory_bytes(depth.width, depth.height, 1, triangles, collapse,
                                              pyramid.texels().float_depths()),
                        source, "the adaptive volume at this bound");
    return room.ok();
  });
  if (!room) return room.error();
  r.balance_seconds = grid.balance_seconds;
  r.emit_seconds = grid.emit_seconds;
  r.quadtree_triangles = grid.num_triangles();
  r.leaves = grid.leaves;
  r.fixup_rounds = grid.fixup_rounds;
  if (collapse) {
    // The closing follows whatever border the grid keeps: no side is locked.
    CollapseReport c;
    grid = collapse_grid(pyramid.texels(), std::move(grid), *bound, {}, &c);
    r.collapses = c.collapses;
    r.collapse_seconds = c.seconds;
  }
  r.grid_triangles = grid.num_triangles();
  const GridQuality quality = grid_quality(grid);
  r.min_angle_degrees = quality.min_angle_degrees;
  r.min_area = quality.min_area;
  if (options.measure) {
    const auto m = std::chrono::steady_clock::now();
    r.max_error_reached = pyramid.measure(grid);
    r.measure_seconds = seconds_since(m);
  }
  const auto a = std::chrono::steady_clock::now();
  Result<Mesh> mesh = assemble_adaptive_volume(light, depth, grid, volume, source);
  r.assemble_seconds = seconds_since(a);
  if (!mesh) return mesh;
  if (Status s = check_representable(*mesh, light, volume.space, volume.light_source); !s)
    return s.error();
  r.vertices = mesh->num_vertices();
  r.triangles = mesh->num_triangles();
  if (report) *report = r;
  return mesh;
}

}  // namespace lightvol
