#include "synthetic_scene.h"

#include <algorithm>
#include <cmath>

namespace lightvol::bench {

DepthImage synthetic_scene(int width, int height) {
  DepthImage d;
  d.width = width;
  d.height = height;
  d.values.resize(static_cast<std::size_t>(width) * height);
  for (int r = 0; r < height; ++r) {
    const double v = (r + 0.5) / height;
    for (int c = 0; c < width; ++c) {
      const double u = (c + 0.5) / width;
      double z = 0.9 - 0.05 * u - 0.03 * v;                                  // floor
      if (u > 0.1 && u < 0.3 && v > 0.15 && v < 0.45) z = std::min(z, 0.6);  // boxes
      if (u > 0.55 && u < 0.9 && v > 0.6 && v < 0.75) z = std::min(z, 0.5 + 0.1 * u);
      if (c % (width / 8) == width / 16 && v > 0.05 && v < 0.95) z = std::min(z, 0.3);  // bars
      if (r == height / 2 && u > 0.3) z = std::min(z, 0.35);
      const double dx = u - 0.65, dy = v - 0.3, rr = 0.15;  // sphere
      if (dx * dx + dy * dy < rr * rr)
        z = std::min(z, 0.55 - std::sqrt(rr * rr - dx * dx - dy * dy));
      d.values[static_cast<std::size_t>(r) * width + c] = static_cast<float>(z);
    }
  }
  return d;
}

}  // namespace lightvol::bench
