// The density ρ(x) of a heterogeneous medium (docs/design.md §6, "Media of varying density"): a
// dimensionless factor that scales the medium's σs and σa at each world point. The homogeneous
// medium is ρ ≡ 1.
//
// The noise field is one fBm of value noise, integer-hashed so that the C++ (double) and GLSL
// (float, shaders/density.glsl) versions give the same field to float rounding:
//
//   lattice value  v(i, seed) = (lowbias32(seed ^ i.x·0x8da6b343 ^ i.y·0xd8163841 ^ i.z·0xcb1ab31f)
//                                >> 8) · 2⁻²³ − 1  ∈ [−1, 1), i the integer lattice point (uint32
//                                arithmetic, i's int32 bits), lowbias32 Chris Wellons' finalizer
//   value noise    n(p, seed) = trilinear blend of v over p's cell with the quintic fade
//                                q(f) = f³(6f² − 15f + 10) of p − floor(p) on each axis
//   fBm            b(x) = Σₒ gainᵒ·n(x·frequency·lacunarityᵒ, seed + o·0x9e3779b9) / Σₒ gainᵒ,
//                                o = 0 … octaves − 1, so b ∈ [−1, 1]
//   density        ρ(x) = max(0, offset + scale·b(x))
//
// Lattice coordinates are meant to stay within ±2²³ (float keeps them exact there).
//
// The voxel field (`"type": "vdb"`) is an OpenVDB grid's voxels made dense over its active
// bounding box: trilinear in the grid's own index space (voxel centres at integer coordinates,
// OpenVDB's BoxSampler), the grid's background value outside the box, mapped to the world by the
// grid's linear transform.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <lightvol/core/math.h>

namespace lightvol {

enum class DensityType { constant, noise, grid };

struct NoiseDensity {
  std::uint32_t seed = 0;
  double frequency = 1.0;   // lattice cells per world unit of the first octave
  int octaves = 4;          // 1 … 12
  double lacunarity = 2.0;  // frequency ratio of successive octaves, ≥ 1
  double gain = 0.5;        // amplitude ratio of successive octaves, [0, 1]
  double offset = 1.0;      // ρ = max(0, offset + scale·b)
  double scale = 0.5;
};

// A scalar field on a voxel grid: `dims` voxels from index `origin` (x fastest in `values`), the
// background outside them, and the affine map from index space to the world.
struct VoxelGrid {
  std::string source;  // "smoke.vdb: grid 'density'", for messages
  std::array<int, 3> origin{0, 0, 0};
  std::array<int, 3> dims{0, 0, 0};
  std::vector<float> values;  // dims[0]·dims[1]·dims[2], all finite and ≥ 0
  double background = 0;      // finite, ≥ 0
  Mat4d index_to_world;       // affine (last row 0 0 0 1), invertible
  Mat4d world_to_index;

  // Sets world_to_index from index_to_world; false when it is not invertible.
  bool set_transform(const Mat4d& to_world);
  double voxel(int i, int j, int k) const;      // background outside the box
  double operator()(const Vec3d& world) const;  // trilinear
  double max_value() const;
  // The shortest world length of a voxel's edges.
  double voxel_size() const;
  // The part [t0, t1] of the line o + t·d within one voxel of the box (where the field may differ
  // from the background), for t in [lo, hi]; false when none of it is.
  bool clip(const Vec3d& o, const Vec3d& d, double lo, double hi, double* t0, double* t1) const;
};

struct Density {
  DensityType type = DensityType::constant;  // constant: ρ ≡ 1 (the homogeneous medium)
  NoiseDensity noise;
  std::shared_ptr<const VoxelGrid> grid;  // type grid

  bool varying() const { return type != DensityType::constant; }
  double operator()(const Vec3d& x) const;  // ρ(x) ≥ 0
  // The largest ρ can be: offset + scale for noise, the largest voxel (or the background) of a
  // grid, 1 when constant.
  double max_density() const;
  // The field's finest feature (world units): the lattice spacing of the finest octave, a grid's
  // voxel size; +infinity for a constant field.
  double finest_wavelength() const;
};

// The fBm b(x) of `noise` (without offset and scale), in [−1, 1].
double noise_fbm(const NoiseDensity& noise, const Vec3d& x);
// One octave's value noise n(p, seed), in [−1, 1).
double value_noise(const Vec3d& p, std::uint32_t seed);

}  // namespace lightvol
