#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <sstream>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

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

  // Grid vertices, row by row; remember the first texel a parallel ray cannot reach.
  std::atomic<std::size_t> first_bad{std::numeric_limits<std::size_t>::max()};
  tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
    for (int r = rows.begin(); r != rows.end(); ++r) {
      const std::size_t row_start = static_cast<std::size_t>(r) * w;
      const int bad_col =
          unproject.row_points(r, &depth.values[row_start], &mesh.positions[3 * row_start]);
      if (bad_col < 0) continue;
      const std::size_t v = row_start + static_cast<std::size_t>(bad_col);
      std::size_t seen = first_bad.load();
      while (v < seen && !first_bad.compare_exchange_weak(seen, v)) {
      }
    }
  });
  if (const std::size_t bad = first_bad.load(); bad != std::numeric_limits<std::size_t>::max()) {
    return unreachable_radial_depth(source, static_cast<int>(bad % w), static_cast<int>(bad / w),
                                    depth.values[bad]);
  }

  // Grid triangles: two per texel quad, wound to face away from the light.
  const bool standard = unproject.standard_winding();
  std::uint32_t* idx = mesh.indices.data();
  const std::uint32_t uw = static_cast<std::uint32_t>(w);
  tbb::parallel_for(tbb::blocked_range<int>(0, h - 1), [&](const tbb::blocked_range<int>& rows) {
    for (int r = rows.begin(); r != rows.end(); ++r) {
      std::uint32_t* out = idx + 6 * static_cast<std::size_t>(r) * (w - 1);
      for (std::uint32_t c = 0; c + 1 < uw; ++c) {
        const std::uint32_t a = static_cast<std::uint32_t>(r) * uw + c, b = a + 1, cc = a + uw,
                            d = cc + 1;
        if (standard) {
          out[0] = a, out[1] = b, out[2] = cc, out[3] = b, out[4] = d, out[5] = cc;
        } else {
          out[0] = a, out[1] = cc, out[2] = b, out[3] = b, out[4] = cc, out[5] = d;
        }
        out += 6;
      }
    }
  });

  // Closing: fan to the apex (spot) or walls and a cap on the near plane (directional).
  std::vector<BorderVertex> ring;
  for (const std::uint32_t v : border_loop(w, h, standard))
    ring.push_back({v, static_cast<int>(v % uw), static_cast<int>(v / uw)});
  append_closing(light.type, unproject, w, h, ring, &mesh);
  LV_CHECK_EQ(mesh.num_vertices(), counts.vertices);
  LV_CHECK_EQ(mesh.num_triangles(), counts.triangles);
  return mesh;
}

Status check_representable(const Mesh& mesh, const Light& light, Space space,
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
  double largest = 0;
  Vec3d lo{std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
           std::numeric_limits<double>::max()};
  Vec3d hi{-lo.x, -lo.y, -lo.z};
  for (std::size_t i = 0; i < mesh.positions.size(); i += 3) {
    const Vec3d p{mesh.positions[i], mesh.positions[i + 1], mesh.positions[i + 2]};
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      return Error{light_source + ": " + frustum_keys +
                   ": the volume's vertices are not finite numbers (near " + shown(light.near) +
                   ", far " + shown(light.far) +
                   ": more than double precision holds); bring far closer to near"};
    largest = std::max({largest, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
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
  std::size_t collapsed = 0;
  for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
    const auto tri = mesh.triangle(t);
    const auto at = [&](std::uint32_t v) {
      return Vec3d{mesh.positions[3 * v], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2]};
    };
    const Vec3d a = at(tri[0]), b = at(tri[1]), c = at(tri[2]);
    const Vec3d n = cross(b - a, c - a);
    if (n.x == 0 && n.y == 0 && n.z == 0) ++collapsed;
  }
  // Float32 steps at the volume's coordinates against the spacing of its vertices (its thinnest
  // extent over the square root of their count, a texel's spacing across a grid): steps coarser
  // than a sixteenth of it move vertices by more than the checks allow for, which then refuse the
  // volume (a spot far from the origin, or a fov of 1e-6 degrees).
  const double thinnest = std::min({span.x, span.y, span.z});
  const double spacing = thinnest / std::sqrt(std::max<double>(1, double(mesh.num_vertices())));
  const bool coarse = largest * std::numeric_limits<float>::epsilon() > spacing / 16;
  if (collapsed == 0 && !coarse) return {};
  const Vec3d extent = hi - lo;
  const double size = std::max({extent.x, extent.y, extent.z});
  const double step = largest * std::numeric_limits<float>::epsilon();
  std::string what = light_source + ": float32 cannot hold this volume (coordinates up to " +
                     shown(largest) + ", steps of " + shown(step) + ", vertices about " +
                     shown(spacing) + " apart; " + std::to_string(collapsed) + " of " +
                     std::to_string(mesh.num_triangles()) + " faces collapse to zero area)";

  if (space == Space::world && largest > 100 * size)
    return Error{what + ": key 'position': the light is far from the origin for the volume's " +
                 "size " + shown(size) +
                 "; write it in the light's eye space with --space light and place it with the "
                 "light's view matrix"};
  return Error{what + ": " + frustum_keys +
               ": the frustum is too thin, or far/near too large, for float32; widen it or bring "
               "near and far closer"};
}

}  // namespace lightvol
