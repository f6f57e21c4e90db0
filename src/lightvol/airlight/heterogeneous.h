// Single-scattering airlight in a medium of varying density (docs/design.md §6, "Media of varying
// density"), by quadrature in double precision: the ground truth of `render --method reference`.
//
// With ρ(x) the medium's density, the light scattered toward the eye from the ray's lit parts is
//
//   ∫ w(s) · σs·ρ(x)·I·p(cos θ)·profile·e^(−τ_L(x)) / d(s)² · e^(−τ_E(s)) ds       (point lights)
//
// (directional lights: no 1/d², irradiance I), where τ_E(s) = σt ∫₀ˢ ρ is the eye-side optical
// depth, τ_L(x) = σt ∫ρ along the light's path to x (from the light position; directional: from
// x's point on the light's near plane, along the light direction), and w(s) the ray's lit weight
// (1 inside the light volume, 0 outside). With ρ ≡ 1 it is the homogeneous La of airlight.h.
#pragma once

#include <vector>

#include <lightvol/airlight/airlight.h>

namespace lightvol {

// The quadrature's panel length for `medium`: a quarter of its density's finest wavelength.
double reference_step(const Medium& medium);

// τ_L(x) = σt ∫ρ along the light's path to x, 4-point Gauss–Legendre on panels of at most `step`.
double light_optical_depth(const Light& light, const Medium& medium, const Vec3d& x, double step);

// σt ∫ρ over the segment a → b, 4-point Gauss–Legendre on panels of at most `step`.
double segment_optical_depth(const Medium& medium, const Vec3d& a, const Vec3d& b, double step);

// A piece [a, b] of the ray with lit weight w (Σ of the light volume's crossing signs beyond it).
struct LitInterval {
  double a = 0, b = 0, weight = 0;
};

// The lit intervals of a ray from its light-volume crossings: `t` the crossing distances (already
// clamped to the visible surface), `sign` +1 where the ray leaves the volume and −1 where it
// enters. Pieces of weight 0 are left out; the result is sorted.
std::vector<LitInterval> lit_intervals(std::vector<std::pair<double, double>> t_and_sign);

// The airlight above over `lit` (sorted, disjoint, a ≥ 0), 4-point Gauss–Legendre panels of at
// most `step` (and, for point lights, a quarter of the distance to the light); the eye-side
// optical depth is integrated along the whole ray from 0.
double heterogeneous_airlight(const Light& light, const Medium& medium, const Ray& ray,
                              const std::vector<LitInterval>& lit, double step);

}  // namespace lightvol
