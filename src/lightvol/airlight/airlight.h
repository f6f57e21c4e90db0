// Single-scattering airlight in a homogeneous medium (docs/design.md §6), in double precision, and
// the medium description that `lightvol render` reads (its camera: light/camera.h).
//
// A ray leaves the eye E along the unit direction ω; La(0, t) is the light scattered toward the eye
// from its first t world units. Summed with signs over a light volume's fragments along the ray
// (+ for back faces, − for front faces, t clamped to the visible surface), it is the pixel's
// airlight with respect to the shadow map.
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <vector>

#include <lightvol/airlight/density.h>
#include <lightvol/core/math.h>
#include <lightvol/core/result.h>
#include <lightvol/light/camera.h>
#include <lightvol/light/light.h>

namespace lightvol {

// ---- phase functions ----------------------------------------------------------------------------

enum class PhaseType { isotropic, hg, schlick };
std::string_view to_string(PhaseType type);

// Phase function over cos θ, θ the angle between the light's propagation direction and the
// direction toward the eye (θ = 0: forward scattering). Normalized over the sphere (1/sr).
struct Phase {
  PhaseType type = PhaseType::isotropic;
  double g = 0;  // Henyey–Greenstein asymmetry, (−1, 1)
  double k = 0;  // Schlick parameter, (−1, 1)

  double operator()(double cos_theta) const;
};

// ---- spotlight profile --------------------------------------------------------------------------

// The soft-edged spotlight of docs/design.md §6, beyond the paper: the intensity is scaled by
// smoothstep(cos outer, cos inner, cos α), α the angle between the light's direction and the
// direction from the light to the point. Angles from the axis, in degrees; off when outer_deg is 0.
struct SpotProfile {
  double inner_deg = 0;
  double outer_deg = 0;

  bool enabled() const { return outer_deg > 0; }
  double operator()(double cos_alpha) const;
};

// ---- medium -------------------------------------------------------------------------------------

struct Medium {
  double scattering = 0.05;  // σs, 1/world unit
  double absorption = 0.0;   // σa, 1/world unit
  double intensity = 1.0;    // I: W/sr for spot and omni lights, W/m² for directional lights
  Phase phase;
  SpotProfile profile;  // spot lights only
  Density density;  // ρ(x) scales σs and σa at x; constant (ρ ≡ 1) unless "density" is given

  double extinction() const { return scattering + absorption; }  // σt (where ρ = 1)
};

// Parses {"scattering", "absorption", "intensity", "phase": {"type": "isotropic"|"hg"|"schlick",
// "g" | "k"}, "profile": {"inner_deg", "outer_deg"}, "density": {"type": "noise", "seed",
// "frequency", "octaves", "lacunarity", "gain", "offset", "scale"}}. All keys optional except
// "scattering" (and the density's "type"); defaults as above and in density.h. Errors name
// `source` and the key: unknown keys, negative coefficients, |g| or |k| ≥ 1, a parameter of another
// phase type, not 0 ≤ inner_deg < outer_deg ≤ 90, an unknown density type, a seed that is not an
// integer in [0, 2³²), octaves not an integer in [1, 12], frequency ≤ 0, lacunarity outside
// [1, 16], gain outside [0, 1], a negative offset or scale.
Result<Medium> parse_medium(std::string_view json_text, const std::string& source);
Result<Medium> load_medium(const std::string& path);

// The medium description `json_text` as a GLB records it beside its light (export.h
// GlbContent::medium_json): checked by parse_medium (its errors name `source`), then written on one
// line without its formatting, keys sorted.
Result<std::string> medium_record_json(std::string_view json_text, const std::string& source);

// ---- airlight -----------------------------------------------------------------------------------

// Sun et al. 2005: F(u, v) = ∫₀ᵛ exp(−u tan ξ) dξ for u ≥ 0, 0 ≤ v ≤ π/2, by Gauss–Legendre.
double sun_f(double u, double v);

// ∫ from a to b of p(cos 2ξ)·exp(−u tan ξ) dξ (0 ≤ a, b ≤ π/2), composite Gauss–Legendre to
// about 1e-12 relative. The point-light integrand of docs/design.md §6.
double phase_integral(const Phase& phase, double u, double a, double b);

// La(0, t) along one ray for one light and medium, in double precision.
class RayAirlight {
 public:
  // `light` gives the type (spot and omni use the point-light formula, directional the closed
  // form), position and direction. `ray.direction` must be unit. A spot light with
  // medium.profile enabled integrates the profile too (adaptive quadrature); others ignore it.
  RayAirlight(const Light& light, const Medium& medium, const Ray& ray);

  // La(0, t) for t ≥ 0 (t = +infinity allowed); 0 for t ≤ 0.
  double operator()(double t) const;

  // Point lights: the distance h of the light from the ray's line, the ray parameter s0 of the
  // point closest to it, and ξ(t) = π/4 + ½·atan((t − s0)/h) (ξ(0) = γ/2).
  double h() const { return h_; }
  double s0() const { return s0_; }
  double xi(double t) const;

 private:
  bool directional_;
  Medium medium_;
  Vec3d light_position_, light_direction_, origin_, direction_;
  bool profiled_ = false;  // a spot light with a SpotProfile
  // point
  double h_ = 0, s0_ = 0, scale_ = 0, xi0_ = 0;
  // directional
  double dir_scale_ = 0, dir_rate_ = 0;
};

}  // namespace lightvol
