#include <algorithm>
#include <cmath>
#include <limits>

#include <lightvol/airlight/heterogeneous.h>
#include <lightvol/core/check.h>

namespace lightvol {

namespace {

// 4-point Gauss–Legendre on [−1, 1] and 3-point for the partial optical depths.
constexpr double kX4[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                           0.8611363115940526};
constexpr double kW4[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                           0.3478548451374538};
constexpr double kX3[3] = {-0.7745966692414834, 0.0, 0.7745966692414834};
constexpr double kW3[3] = {0.5555555555555556, 0.8888888888888888, 0.5555555555555556};

// ∫ρ over the segment p → q, GL4 on `panels` equal panels.
double segment_density(const Density& density, const Vec3d& p, const Vec3d& q, int panels) {
  const Vec3d d = q - p;
  double sum = 0;
  for (int k = 0; k < panels; ++k) {
    const double mid = (k + 0.5) / panels, half = 0.5 / panels;
    for (int i = 0; i < 4; ++i) sum += kW4[i] * density(p + (mid + half * kX4[i]) * d);
  }
  return sum * 0.5 / panels * length(d);
}

}  // namespace

double reference_step(const Medium& medium) { return 0.25 * medium.density.finest_wavelength(); }

double segment_optical_depth(const Medium& medium, const Vec3d& a, const Vec3d& b, double step) {
  LV_CHECK(step > 0);
  const int panels = std::max(1, static_cast<int>(std::ceil(length(b - a) / step)));
  return medium.extinction() * segment_density(medium.density, a, b, panels);
}

double light_optical_depth(const Light& light, const Medium& medium, const Vec3d& x, double step) {
  Vec3d from = light.position;
  if (light.type == LightType::directional) {
    const double z = dot(x - light.position, light.direction) - light.near;
    from = x - z * light.direction;
  }
  const double len = length(x - from);
  if (!(len > 0)) return 0;
  const Density& rho = medium.density;
  if (rho.type == DensityType::grid) {
    // The background beyond the grid's box exactly; quadrature over the part within it.
    const Vec3d d = (1.0 / len) * (x - from);
    double t0 = 0, t1 = 0;
    if (!rho.grid->clip(from, d, 0, len, &t0, &t1))
      return medium.extinction() * rho.grid->background * len;
    const int panels = std::max(1, static_cast<int>(std::ceil((t1 - t0) / step)));
    return medium.extinction() * (rho.grid->background * (len - (t1 - t0)) +
                                  segment_density(rho, from + t0 * d, from + t1 * d, panels));
  }
  const int panels = std::max(1, static_cast<int>(std::ceil(len / step)));
  return medium.extinction() * segment_density(rho, from, x, panels);
}

std::vector<LitInterval> lit_intervals(std::vector<std::pair<double, double>> t_and_sign) {
  std::sort(t_and_sign.begin(), t_and_sign.end());
  double weight = 0;  // Σ of the signs beyond the current piece
  for (const auto& [t, sign] : t_and_sign) weight += sign;
  std::vector<LitInterval> out;
  double from = 0;
  for (const auto& [t, sign] : t_and_sign) {
    if (weight != 0 && t > from) out.push_back({from, t, weight});
    from = std::max(from, t);
    weight -= sign;
  }
  return out;
}

double heterogeneous_airlight(const Light& light, const Medium& medium, const Ray& ray,
                              const std::vector<LitInterval>& lit, double step) {
  if (lit.empty()) return 0;
  LV_CHECK(step > 0);
  const Density& rho = medium.density;
  const double st = medium.extinction();
  const bool directional = light.type == LightType::directional;
  const bool profiled = light.type == LightType::spot && medium.profile.enabled();
  const auto at = [&](double s) { return ray.origin + s * ray.direction; };
  // The integrand without e^(−τ_E): σs·ρ·I·p·profile·e^(−τ_L)/d².
  const auto source = [&](double s, double density) {
    if (density <= 0) return 0.0;
    const Vec3d x = at(s);
    const double tau_l = light_optical_depth(light, medium, x, step);
    if (directional)
      return medium.scattering * density * medium.intensity *
             medium.phase(-dot(ray.direction, light.direction)) * std::exp(-tau_l);
    const Vec3d to_x = x - light.position;
    const double d2 = dot(to_x, to_x);
    const double d = std::sqrt(d2);
    const double cos_theta = d > 0 ? -dot(to_x, ray.direction) / d : 1.0;
    const double profile = profiled && d > 0 ? medium.profile(dot(to_x, light.direction) / d) : 1.0;
    return medium.scattering * density * medium.intensity * medium.phase(cos_theta) * profile *
           std::exp(-tau_l) / d2;
  };
  double tau_e = 0, sum = 0, s = 0;
  // A grid of background 0 scatters nothing and hides nothing outside its box: only the part of
  // the ray within it counts.
  double support_end = std::numeric_limits<double>::infinity();
  if (rho.type == DensityType::grid && rho.grid->background == 0) {
    double t0 = 0, t1 = 0;
    if (!rho.grid->clip(ray.origin, ray.direction, 0, lit.back().b, &t0, &t1)) return 0;
    s = t0;
    support_end = t1;
  }
  for (LitInterval piece : lit) {
    piece.a = std::max(piece.a, s);
    piece.b = std::min(piece.b, support_end);
    if (!(piece.b > piece.a)) continue;
    // Dark stretch before the piece: only the eye-side optical depth.
    while (s < piece.a) {
      const double b = std::min(piece.a, s + step);
      tau_e += st * segment_density(rho, at(s), at(b), 1);
      s = b;
    }
    while (s < piece.b) {
      double len = step;
      if (!directional) len = std::min(len, std::max(0.25 * length(at(s) - light.position), 1e-9));
      const double b = std::min(piece.b, s + len);
      const double mid = 0.5 * (s + b), half = 0.5 * (b - s);
      double density_integral = 0;
      for (int i = 0; i < 4; ++i) {
        const double node = mid + half * kX4[i];
        const double density = rho(at(node));
        density_integral += kW4[i] * density;
        // τ_E at the node: τ_E(s) + σt ∫ from s to the node of ρ (3-point Gauss–Legendre).
        const double m = 0.5 * (s + node), hh = 0.5 * (node - s);
        double partial = 0;
        for (int j = 0; j < 3; ++j) partial += kW3[j] * rho(at(m + hh * kX3[j]));
        sum += piece.weight * kW4[i] * half * source(node, density) *
               std::exp(-(tau_e + st * partial * hh));
      }
      tau_e += st * density_integral * half;
      s = b;
    }
  }
  return sum;
}

}  // namespace lightvol
