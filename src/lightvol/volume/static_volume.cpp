#include <atomic>
#include <limits>

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

}  // namespace lightvol
