#include <algorithm>
#include <cmath>
#include <limits>

#include <lightvol/airlight/density.h>

namespace lightvol {

namespace {

std::uint32_t lowbias32(std::uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x;
}

// The int32 bits of floor(p) as uint32 (wrapping beyond int32, where float has long lost the
// lattice anyway).
std::uint32_t lattice(double floor_p) {
  return static_cast<std::uint32_t>(static_cast<std::int64_t>(floor_p));
}

double lattice_value(std::uint32_t seed, std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  const std::uint32_t h =
      lowbias32(seed ^ (x * 0x8da6b343u) ^ (y * 0xd8163841u) ^ (z * 0xcb1ab31fu));
  return static_cast<double>(h >> 8) * (1.0 / 8388608.0) - 1.0;
}

double fade(double f) { return f * f * f * (f * (f * 6.0 - 15.0) + 10.0); }

}  // namespace

double value_noise(const Vec3d& p, std::uint32_t seed) {
  const double fx = std::floor(p.x), fy = std::floor(p.y), fz = std::floor(p.z);
  const std::uint32_t ix = lattice(fx), iy = lattice(fy), iz = lattice(fz);
  const double ux = fade(p.x - fx), uy = fade(p.y - fy), uz = fade(p.z - fz);
  double c[2][2];
  for (int dz = 0; dz < 2; ++dz)
    for (int dy = 0; dy < 2; ++dy) {
      const double a = lattice_value(seed, ix, iy + dy, iz + dz);
      const double b = lattice_value(seed, ix + 1, iy + dy, iz + dz);
      c[dz][dy] = a + ux * (b - a);
    }
  const double y0 = c[0][0] + uy * (c[0][1] - c[0][0]);
  const double y1 = c[1][0] + uy * (c[1][1] - c[1][0]);
  return y0 + uz * (y1 - y0);
}

double noise_fbm(const NoiseDensity& noise, const Vec3d& x) {
  double sum = 0, norm = 0, amplitude = 1, frequency = noise.frequency;
  std::uint32_t seed = noise.seed;
  for (int o = 0; o < noise.octaves; ++o) {
    sum += amplitude * value_noise(x * frequency, seed);
    norm += amplitude;
    amplitude *= noise.gain;
    frequency *= noise.lacunarity;
    seed += 0x9e3779b9u;
  }
  return sum / norm;
}

double Density::operator()(const Vec3d& x) const {
  if (type == DensityType::constant) return 1.0;
  return std::max(0.0, noise.offset + noise.scale * noise_fbm(noise, x));
}

double Density::max_density() const {
  return type == DensityType::constant ? 1.0 : noise.offset + noise.scale;
}

double Density::finest_wavelength() const {
  if (type == DensityType::constant) return std::numeric_limits<double>::infinity();
  return 1.0 / (noise.frequency * std::pow(noise.lacunarity, noise.octaves - 1));
}

}  // namespace lightvol
