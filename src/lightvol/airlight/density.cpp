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

// ---- voxel grids
// ---------------------------------------------------------------------------------

bool VoxelGrid::set_transform(const Mat4d& to_world) {
  bool ok = false;
  const Mat4d inv = inverse(to_world, &ok);
  if (!ok || !std::isfinite(determinant(to_world)) || determinant(to_world) == 0) return false;
  index_to_world = to_world;
  world_to_index = inv;
  return true;
}

double VoxelGrid::voxel(int i, int j, int k) const {
  i -= origin[0];
  j -= origin[1];
  k -= origin[2];
  if (i < 0 || j < 0 || k < 0 || i >= dims[0] || j >= dims[1] || k >= dims[2]) return background;
  return values[(static_cast<std::size_t>(k) * dims[1] + j) * dims[0] + i];
}

double VoxelGrid::operator()(const Vec3d& world) const {
  const Vec3d p = world_to_index.transform_point(world);
  const double fx = std::floor(p.x), fy = std::floor(p.y), fz = std::floor(p.z);
  // Far outside the box (and beyond int): the background.
  const auto outside = [](double f, int lo, int n) { return f < lo - 1.0 || f > lo + n * 1.0; };
  if (outside(fx, origin[0], dims[0]) || outside(fy, origin[1], dims[1]) ||
      outside(fz, origin[2], dims[2]))
    return background;
  const int ix = static_cast<int>(fx), iy = static_cast<int>(fy), iz = static_cast<int>(fz);
  const double ux = p.x - fx, uy = p.y - fy, uz = p.z - fz;
  double c[2][2];
  for (int dz = 0; dz < 2; ++dz)
    for (int dy = 0; dy < 2; ++dy) {
      const double a = voxel(ix, iy + dy, iz + dz), b = voxel(ix + 1, iy + dy, iz + dz);
      c[dz][dy] = a + ux * (b - a);
    }
  const double y0 = c[0][0] + uy * (c[0][1] - c[0][0]);
  const double y1 = c[1][0] + uy * (c[1][1] - c[1][0]);
  return y0 + uz * (y1 - y0);
}

double VoxelGrid::max_value() const {
  double m = background;
  for (float v : values) m = std::max(m, static_cast<double>(v));
  return m;
}

double VoxelGrid::voxel_size() const {
  double size = std::numeric_limits<double>::infinity();
  for (const Vec3d axis : {Vec3d{1, 0, 0}, Vec3d{0, 1, 0}, Vec3d{0, 0, 1}})
    size = std::min(size, length(index_to_world.transform_vector(axis)));
  return size;
}

bool VoxelGrid::clip(const Vec3d& o, const Vec3d& d, double lo, double hi, double* t0,
                     double* t1) const {
  // An affine map keeps the line's parameter: clip in index space, to the box grown by a voxel
  // (trilinear blends the last voxels with the background over one more).
  const Vec3d io = world_to_index.transform_point(o), id = world_to_index.transform_vector(d);
  const double os[3] = {io.x, io.y, io.z}, ds[3] = {id.x, id.y, id.z};
  double a = lo, b = hi;
  for (int axis = 0; axis < 3; ++axis) {
    const double box_lo = origin[axis] - 1.0, box_hi = origin[axis] + dims[axis] * 1.0;
    if (ds[axis] == 0) {
      if (os[axis] < box_lo || os[axis] > box_hi) return false;
      continue;
    }
    double ta = (box_lo - os[axis]) / ds[axis], tb = (box_hi - os[axis]) / ds[axis];
    if (ta > tb) std::swap(ta, tb);
    a = std::max(a, ta);
    b = std::min(b, tb);
  }
  if (!(b > a)) return false;
  *t0 = a;
  *t1 = b;
  return true;
}

// ---- the density --------------------------------------------------------------------------------

double Density::operator()(const Vec3d& x) const {
  if (type == DensityType::constant) return 1.0;
  if (type == DensityType::grid) return (*grid)(x);
  return std::max(0.0, noise.offset + noise.scale * noise_fbm(noise, x));
}

double Density::max_density() const {
  if (type == DensityType::grid) return grid->max_value();
  return type == DensityType::constant ? 1.0 : noise.offset + noise.scale;
}

double Density::finest_wavelength() const {
  if (type == DensityType::constant) return std::numeric_limits<double>::infinity();
  if (type == DensityType::grid) return grid->voxel_size();
  return 1.0 / (noise.frequency * std::pow(noise.lacunarity, noise.octaves - 1));
}

}  // namespace lightvol
