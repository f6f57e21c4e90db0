// heightfield_tool: the synthetic benchmark maps and an error measure shared by every mesher in
// the Martini comparison (tests/bench/martini_bench.sh).
//
//   heightfield_tool map N OUT.exr OUT.f32
//       the synthetic scene (synthetic_scene.h) at N×N, as EXR for lightvol and raw float32 for
//       node.
//   heightfield_tool error MAP.f32 N MESH [XY_SCALE]
//       MESH is a lightvol PLY built with the benchmark's directional light (world point of texel
//       (col, row) at depth z is (col, −row, −z) / (XY_SCALE, XY_SCALE, 1); XY_SCALE 1 unless
//       given, N − 1 for a light box one unit across), or a Martini .mrt dump (uint32 vertex and
//       triangle counts, uint32 (x, y) pairs, uint32 index triples; heights from the map). Prints
//       "triangles N max_error E uncovered U": for every texel, the triangle over it is found by
//       rasterizing each triangle's lattice points, its height interpolated linearly and compared
//       with the map. The closing of a volume (vertices on the near plane, z = 0) is dropped first.
//       Nothing here knows how either mesh was made. Also prints "min_angle A": the triangles'
//       smallest angle in degrees, in texel space.
//   heightfield_tool from IN N SCALE OUT.exr OUT.f32
//       a real N×N depth image (e.g. a shadow map of `lightvol shadowmap` with linear depth) as a
//       height field: every value times SCALE (e.g. 1/far, so that values lie in [0, 1]).
//   heightfield_tool steps N OUT.exr OUT.f32
//       plateaus with steps that cascade: 2×2-texel plateaus on a floor at height 0.5, in every
//       8-column, 16-row tile one 0.0009 higher and one 0.0004 lower, and a cliff (0.7) along the
//       left edge. At E = 0.001 (the benchmark's light box) the leaf next to the cliff's cells
//       breaks the bound once its neighbour splits, and splitting it makes the next one split: the
//       fix-up rounds walk across the map one 8-texel cell each (N / 8 of them).
//   heightfield_tool upsample IN K OUT.exr OUT.f32
//       a depth image K times larger each way, every texel repeated K×K times: plateaus and
//       one-texel steps, what a high-resolution map of a simple scene looks like.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include "synthetic_scene.h"

namespace {

struct Tri {
  double x[3], y[3], z[3];
};

std::vector<char> slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

bool read_ply(const std::string& path, double xy_scale, std::vector<Tri>* out) {
  const std::vector<char> bytes = slurp(path);
  const std::string text(bytes.begin(), bytes.begin() + std::min<std::size_t>(bytes.size(), 4096));
  const std::size_t end = text.find("end_header\n");
  if (end == std::string::npos) return false;
  const std::size_t nv = std::stoul(text.substr(text.find("element vertex ") + 15));
  const std::size_t nf = std::stoul(text.substr(text.find("element face ") + 13));
  const char* p = bytes.data() + end + 11;
  std::vector<float> pos(3 * nv);
  std::memcpy(pos.data(), p, 12 * nv);
  p += 12 * nv;
  for (std::size_t f = 0; f < nf; ++f) {
    std::uint32_t idx[3];
    std::memcpy(idx, p + 1, 12);
    p += 13;
    Tri t;
    bool closing = false;
    for (int k = 0; k < 3; ++k) {
      t.x[k] = static_cast<float>(std::round(pos[3 * idx[k]] * xy_scale));
      t.y[k] = static_cast<float>(std::round(-pos[3 * idx[k] + 1] * xy_scale));
      t.z[k] = -pos[3 * idx[k] + 2];
      closing = closing || t.z[k] <= 1e-7;
    }
    if (!closing) out->push_back(t);
  }
  return true;
}

bool read_mrt(const std::string& path, const std::vector<float>& map, int n,
              std::vector<Tri>* out) {
  const std::vector<char> bytes = slurp(path);
  if (bytes.size() < 8) return false;
  std::uint32_t nv = 0, nt = 0;
  std::memcpy(&nv, bytes.data(), 4);
  std::memcpy(&nt, bytes.data() + 4, 4);
  std::vector<std::uint32_t> v(2 * nv), t(3 * nt);
  std::memcpy(v.data(), bytes.data() + 8, 8 * nv);
  std::memcpy(t.data(), bytes.data() + 8 + 8 * nv, 12 * nt);
  for (std::uint32_t f = 0; f < nt; ++f) {
    Tri tri;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t i = t[3 * f + k];
      tri.x[k] = v[2 * i];
      tri.y[k] = v[2 * i + 1];
      tri.z[k] = map[static_cast<std::size_t>(v[2 * i + 1]) * n + v[2 * i]];
    }
    out->push_back(tri);
  }
  return true;
}

int measure(const std::string& map_path, int n, const std::string& mesh_path, double xy_scale) {
  std::vector<float> map(static_cast<std::size_t>(n) * n);
  {
    const std::vector<char> bytes = slurp(map_path);
    if (bytes.size() != 4 * map.size()) {
      std::fprintf(stderr, "heightfield_tool: %s: expected %zu bytes\n", map_path.c_str(),
                   4 * map.size());
      return 2;
    }
    std::memcpy(map.data(), bytes.data(), bytes.size());
  }
  std::vector<Tri> tris;
  const bool ok = mesh_path.size() > 4 && mesh_path.substr(mesh_path.size() - 4) == ".ply"
                      ? read_ply(mesh_path, xy_scale, &tris)
                      : read_mrt(mesh_path, map, n, &tris);
  if (!ok) {
    std::fprintf(stderr, "heightfield_tool: cannot read %s\n", mesh_path.c_str());
    return 2;
  }
  std::vector<float> err(map.size(), -1.0f);
  double min_angle = 180;
  for (const Tri& t : tris) {
    const double area2 =
        (t.x[1] - t.x[0]) * (t.y[2] - t.y[0]) - (t.x[2] - t.x[0]) * (t.y[1] - t.y[0]);
    if (area2 == 0) continue;
    for (int c = 0; c < 3; ++c) {
      const int a = (c + 1) % 3, b = (c + 2) % 3;
      const double ux = t.x[a] - t.x[c], uy = t.y[a] - t.y[c], vx = t.x[b] - t.x[c],
                   vy = t.y[b] - t.y[c];
      min_angle = std::min(min_angle, std::atan2(std::abs(area2), ux * vx + uy * vy) * 180 / M_PI);
    }
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({t.x[0], t.x[1], t.x[2]}))));
    const int x1 = std::min(n - 1, static_cast<int>(std::ceil(std::max({t.x[0], t.x[1], t.x[2]}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({t.y[0], t.y[1], t.y[2]}))));
    const int y1 = std::min(n - 1, static_cast<int>(std::ceil(std::max({t.y[0], t.y[1], t.y[2]}))));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        // Barycentrics by exact edge functions (integer vertex coordinates).
        const double w0 = ((t.x[1] - x) * (t.y[2] - y) - (t.x[2] - x) * (t.y[1] - y)) / area2;
        const double w1 = ((t.x[2] - x) * (t.y[0] - y) - (t.x[0] - x) * (t.y[2] - y)) / area2;
        const double w2 = 1 - w0 - w1;
        if (w0 < 0 || w1 < 0 || w2 < -1e-12) continue;
        const double z = w0 * t.z[0] + w1 * t.z[1] + w2 * t.z[2];
        const std::size_t k = static_cast<std::size_t>(y) * n + x;
        err[k] = std::max(err[k], static_cast<float>(std::abs(z - map[k])));
      }
  }
  double worst = 0;
  long uncovered = 0;
  for (const float e : err) {
    if (e < 0) ++uncovered;
    worst = std::max(worst, static_cast<double>(e));
  }
  std::printf("triangles %zu max_error %.6g uncovered %ld min_angle %.4g\n", tris.size(), worst,
              uncovered, min_angle);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 5 && std::string(argv[1]) == "map") {
    const int n = std::atoi(argv[2]);
    const lightvol::DepthImage d = lightvol::bench::synthetic_scene(n, n);
    if (const lightvol::Status s = lightvol::write_depth_image(argv[3], d); !s) {
      std::fprintf(stderr, "heightfield_tool: %s\n", s.error().message.c_str());
      return 2;
    }
    std::ofstream(argv[4], std::ios::binary)
        .write(reinterpret_cast<const char*>(d.values.data()),
               static_cast<std::streamsize>(4 * d.values.size()));
    return 0;
  }
  if (argc == 7 && std::string(argv[1]) == "from") {
    const int n = std::atoi(argv[3]);
    const double scale = std::atof(argv[4]);
    lightvol::Result<lightvol::DepthImage> d = lightvol::read_depth_image(argv[2], {});
    if (!d || d->width != n || d->height != n) {
      std::fprintf(stderr, "heightfield_tool: %s: not a readable %dx%d depth image\n", argv[2], n,
                   n);
      return 2;
    }
    for (float& v : d->values) v = static_cast<float>(v * scale);
    if (const lightvol::Status s = lightvol::write_depth_image(argv[5], *d); !s) {
      std::fprintf(stderr, "heightfield_tool: %s\n", s.error().message.c_str());
      return 2;
    }
    std::ofstream(argv[6], std::ios::binary)
        .write(reinterpret_cast<const char*>(d->values.data()),
               static_cast<std::streamsize>(4 * d->values.size()));
    return 0;
  }
  if (argc == 5 && std::string(argv[1]) == "steps") {
    const int n = std::atoi(argv[2]);
    lightvol::DepthImage d;
    d.width = d.height = n;
    d.values.resize(static_cast<std::size_t>(n) * static_cast<std::size_t>(n));
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c) {
        const int pc = c / 2 * 2, pr = r % 16 / 2 * 2;  // the plateau's first texel
        float v = 0.5f;
        if (pc < 2) {
          v = 0.7f;
        } else if (pc % 8 == 0 && pr == 4) {
          v = 0.5009f;
        } else if (pc % 8 == 2 && pr == 2) {
          v = 0.4996f;
        }
        d.values[static_cast<std::size_t>(r) * static_cast<std::size_t>(n) + c] = v;
      }
    if (const lightvol::Status s = lightvol::write_depth_image(argv[3], d); !s) {
      std::fprintf(stderr, "heightfield_tool: %s\n", s.error().message.c_str());
      return 2;
    }
    std::ofstream(argv[4], std::ios::binary)
        .write(reinterpret_cast<const char*>(d.values.data()),
               static_cast<std::streamsize>(4 * d.values.size()));
    return 0;
  }
  if (argc == 6 && std::string(argv[1]) == "upsample") {
    const int k = std::atoi(argv[3]);
    lightvol::Result<lightvol::DepthImage> d = lightvol::read_depth_image(argv[2], {});
    if (!d || k < 1) {
      std::fprintf(stderr, "heightfield_tool: %s: not a readable depth image, or K < 1\n", argv[2]);
      return 2;
    }
    lightvol::DepthImage up;
    up.width = d->width * k;
    up.height = d->height * k;
    up.values.resize(static_cast<std::size_t>(up.width) * static_cast<std::size_t>(up.height));
    for (int r = 0; r < up.height; ++r)
      for (int c = 0; c < up.width; ++c)
        up.values[static_cast<std::size_t>(r) * static_cast<std::size_t>(up.width) + c] =
            d->at(c / k, r / k);
    if (const lightvol::Status s = lightvol::write_depth_image(argv[4], up); !s) {
      std::fprintf(stderr, "heightfield_tool: %s\n", s.error().message.c_str());
      return 2;
    }
    std::ofstream(argv[5], std::ios::binary)
        .write(reinterpret_cast<const char*>(up.values.data()),
               static_cast<std::streamsize>(4 * up.values.size()));
    return 0;
  }
  if ((argc == 5 || argc == 6) && std::string(argv[1]) == "error")
    return measure(argv[2], std::atoi(argv[3]), argv[4], argc == 6 ? std::atof(argv[5]) : 1.0);
  std::fprintf(
      stderr,
      "usage: heightfield_tool map N OUT.exr OUT.f32 | error MAP.f32 N MESH.{ply,mrt} [XY_SCALE] | "
      "from IN N SCALE OUT.exr OUT.f32 | steps N OUT.exr OUT.f32 | upsample IN K OUT.exr "
      "OUT.f32\n");
  return 2;
}
