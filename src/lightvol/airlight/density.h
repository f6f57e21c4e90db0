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
#pragma once

#include <cstdint>
#include <string>

#include <lightvol/core/math.h>

namespace lightvol {

enum class DensityType { constant, noise };

struct NoiseDensity {
  std::uint32_t seed = 0;
  double frequency = 1.0;   // lattice cells per world unit of the first octave
  int octaves = 4;          // 1 … 12
  double lacunarity = 2.0;  // frequency ratio of successive octaves, ≥ 1
  double gain = 0.5;        // amplitude ratio of successive octaves, [0, 1]
  double offset = 1.0;      // ρ = max(0, offset + scale·b)
  double scale = 0.5;
};

struct Density {
  DensityType type = DensityType::constant;  // constant: ρ ≡ 1 (the homogeneous medium)
  NoiseDensity noise;

  bool varying() const { return type != DensityType::constant; }
  double operator()(const Vec3d& x) const;  // ρ(x) ≥ 0
  // The largest ρ can be: offset + scale for noise, 1 when constant.
  double max_density() const;
  // The lattice spacing of the finest octave (world units): the field's finest feature.
  // +infinity for a constant field.
  double finest_wavelength() const;
};

// The fBm b(x) of `noise` (without offset and scale), in [−1, 1].
double noise_fbm(const NoiseDensity& noise, const Vec3d& x);
// One octave's value noise n(p, seed), in [−1, 1).
double value_noise(const Vec3d& p, std::uint32_t seed);

}  // namespace lightvol
