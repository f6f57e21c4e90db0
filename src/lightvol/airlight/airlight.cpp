#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>
#include <sstream>
#include <utility>

#include <nlohmann/json.hpp>

#include <lightvol/airlight/airlight.h>
#include <lightvol/airlight/detail/vdb_file.h>
#include <lightvol/core/check.h>
#include <lightvol/core/detail/json_keys.h>
#include <lightvol/light/texel.h>

namespace lightvol {

std::string_view to_string(PhaseType type) {
  switch (type) {
    case PhaseType::isotropic:
      return "isotropic";
    case PhaseType::hg:
      return "hg";
    case PhaseType::schlick:
      return "schlick";
  }
  return "?";
}

double Phase::operator()(double cos_theta) const {
  constexpr double inv4pi = 1.0 / (4.0 * std::numbers::pi);
  switch (type) {
    case PhaseType::isotropic:
      return inv4pi;
    case PhaseType::hg: {
      const double denom = 1.0 + g * g - 2.0 * g * cos_theta;
      return inv4pi * (1.0 - g * g) / (denom * std::sqrt(denom));
    }
    case PhaseType::schlick: {
      const double denom = 1.0 - k * cos_theta;
      return inv4pi * (1.0 - k * k) / (denom * denom);
    }
  }
  return inv4pi;
}

double SpotProfile::operator()(double cos_alpha) const {
  if (!enabled()) return 1.0;
  const double lo = std::cos(outer_deg * std::numbers::pi / 180.0);
  const double hi = std::cos(inner_deg * std::numbers::pi / 180.0);
  const double x = std::clamp((cos_alpha - lo) / (hi - lo), 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

// ---- JSON ---------------------------------------------------------------------------------------

namespace {

using nlohmann::json;

// A number of `reader` at `key` within [lo, hi] (an integer when `integer`), else an error naming
// the key.
Result<double> bounded_number(const KeyReader& reader, const char* key, double lo, double hi,
                              bool integer, const std::string& range) {
  Result<double> x = reader.number(key);
  if (!x) return x.error();
  if (!(*x >= lo && *x <= hi) || (integer && std::floor(*x) != *x))
    return reader.error(key, "must be " + range + ", got " + format_number(*x));
  return *x;
}

// {"type": "vdb", "file", "grid", "scale"}: the grid read from the file (a relative path is
// relative to the folder of `source`, the medium's file), its values and background times `scale`.
Result<Density> parse_vdb_density(const KeyReader& d, const std::string& source) {
  if (Status s = d.only({"type", "file", "grid", "scale"}); !s) return s.error();
  Result<std::string> file = d.string("file");
  if (!file) return file.error();
  if (file->empty()) return d.error("file", "must name an OpenVDB file");
  std::string grid = "density";
  if (d.has("grid")) {
    Result<std::string> name = d.string("grid");
    if (!name) return name.error();
    grid = *name;
  }
  double scale = 1;
  if (d.has("scale")) {
    Result<double> x =
        bounded_number(d, "scale", 0, std::numeric_limits<double>::max(), false, ">= 0");
    if (!x) return x.error();
    scale = *x;
  }
  std::filesystem::path path(*file);
  if (path.is_relative()) path = std::filesystem::path(source).parent_path() / path;
  Result<std::shared_ptr<const VoxelGrid>> read = detail::read_vdb_grid(path.string(), grid);
  if (!read) return d.error("file", read.error().message);
  std::shared_ptr<const VoxelGrid> voxels = *read;
  if (scale != 1) {
    auto scaled = std::make_shared<VoxelGrid>(*voxels);
    for (float& v : scaled->values) v = static_cast<float>(v * scale);
    scaled->background *= scale;
    for (float v : scaled->values)
      if (!std::isfinite(v))
        return d.error("scale", "makes a voxel of " + voxels->source + " beyond float's range");
    voxels = std::move(scaled);
  }
  Density density;
  density.type = DensityType::grid;
  density.grid = std::move(voxels);
  return density;
}

// The medium's "density" object (docs/design.md §6).
Result<Density> parse_density(const KeyReader& keys, const std::string& source) {
  Result<KeyReader> object = keys.object("density");
  if (!object) return object.error();
  const KeyReader& d = *object;
  Result<std::string> type = d.string("type");
  if (!type) return type.error();
  if (*type == "vdb") return parse_vdb_density(d, source);
  if (*type != "noise")
    return d.error("type", "expected \"noise\" or \"vdb\", got " + quote_text(*type));
  if (Status s =
          d.only({"type", "seed", "frequency", "octaves", "lacunarity", "gain", "offset", "scale"});
      !s)
    return s.error();
  Density density;
  density.type = DensityType::noise;
  NoiseDensity& n = density.noise;
  const double inf = std::numeric_limits<double>::infinity();
  struct Field {
    const char* key;
    double lo, hi;
    bool integer;
    const char* range;
  };
  for (const Field& f :
       {Field{"seed", 0, 4294967295.0, true, "an integer in [0, 4294967295]"},
        Field{"frequency", 0, inf, false, "> 0"},
        Field{"octaves", 1, 12, true, "an integer in [1, 12]"},
        Field{"lacunarity", 1, 16, false, "in [1, 16]"}, Field{"gain", 0, 1, false, "in [0, 1]"},
        Field{"offset", 0, inf, false, ">= 0"}, Field{"scale", 0, inf, false, ">= 0"}}) {
    if (!d.has(f.key)) continue;
    Result<double> x = bounded_number(d, f.key, f.lo, f.hi, f.integer, f.range);
    if (!x) return x.error();
    if (std::string_view(f.key) == "frequency" && !(*x > 0))
      return d.error(f.key, "must be > 0, got " + format_number(*x));
    const std::string_view key = f.key;
    if (key == "seed") n.seed = static_cast<std::uint32_t>(*x);
    if (key == "frequency") n.frequency = *x;
    if (key == "octaves") n.octaves = static_cast<int>(*x);
    if (key == "lacunarity") n.lacunarity = *x;
    if (key == "gain") n.gain = *x;
    if (key == "offset") n.offset = *x;
    if (key == "scale") n.scale = *x;
  }
  return density;
}

}  // namespace

Result<Medium> parse_medium(std::string_view json_text, const std::string& source) {
  Result<json> root = parse_json_object(json_text, source, "a medium");
  if (!root) return root.error();
  const KeyReader keys(*root, source);
  if (Status s =
          keys.only({"scattering", "absorption", "intensity", "phase", "profile", "density"});
      !s)
    return s.error();
  Medium medium;
  if (!keys.has("scattering")) return keys.error("scattering", "missing");
  for (auto [key, field] :
       {std::pair{"scattering", &medium.scattering}, std::pair{"absorption", &medium.absorption},
        std::pair{"intensity", &medium.intensity}}) {
    if (!keys.has(key)) continue;
    Result<double> x = keys.number(key);
    if (!x) return x.error();
    if (*x < 0) return keys.error(key, "must be >= 0, got " + format_number(*x));
    *field = *x;
  }
  if (keys.has("phase")) {
    Result<KeyReader> phase = keys.object("phase");
    if (!phase) return phase.error();
    if (Status s = phase->only({"type", "g", "k"}); !s) return s.error();
    Result<std::string> type = phase->string("type");
    if (!type) return type.error();
    std::string parameter;
    if (*type == "isotropic") {
      medium.phase.type = PhaseType::isotropic;
    } else if (*type == "hg") {
      medium.phase.type = PhaseType::hg;
      parameter = "g";
    } else if (*type == "schlick") {
      medium.phase.type = PhaseType::schlick;
      parameter = "k";
    } else {
      return phase->error(
          "type", "expected \"isotropic\", \"hg\" or \"schlick\", got " + quote_text(*type));
    }
    for (const char* key : {"g", "k"}) {
      if (!phase->has(key)) continue;
      if (parameter != key)
        return phase->error(key, "does not apply to a phase of type " + quote_text(*type));
      Result<double> x = phase->number(key);
      if (!x) return x.error();
      if (!(std::abs(*x) < 1))
        return phase->error(key, "must lie in (-1, 1), got " + format_number(*x));
      (parameter == "g" ? medium.phase.g : medium.phase.k) = *x;
    }
  }
  if (keys.has("profile")) {
    Result<KeyReader> profile = keys.object("profile");
    if (!profile) return profile.error();
    if (Status s = profile->only({"inner_deg", "outer_deg"}); !s) return s.error();
    for (auto [key, field] : {std::pair{"inner_deg", &medium.profile.inner_deg},
                              std::pair{"outer_deg", &medium.profile.outer_deg}}) {
      Result<double> x = profile->number(key);
      if (!x) return x.error();
      *field = *x;
    }
    if (!(medium.profile.inner_deg >= 0 && medium.profile.inner_deg < medium.profile.outer_deg &&
          medium.profile.outer_deg <= 90))
      return keys.error("profile", "needs 0 <= inner_deg < outer_deg <= 90, got " +
                                       format_number(medium.profile.inner_deg) + " and " +
                                       format_number(medium.profile.outer_deg));
  }
  if (keys.has("density")) {
    Result<Density> density = parse_density(keys, source);
    if (!density) return density.error();
    medium.density = *density;
  }
  return medium;
}

Result<Medium> load_medium(const std::string& path) {
  Result<std::string> text = read_text_file(path, "medium description");
  if (!text) return text.error();
  return parse_medium(*text, path);
}

Result<std::string> medium_record_json(std::string_view json_text, const std::string& source) {
  if (Result<Medium> medium = parse_medium(json_text, source); !medium) return medium.error();
  const nlohmann::json medium = nlohmann::json::parse(json_text, nullptr, false);
  if (medium.is_discarded()) return Error{source + ": not JSON"};  // parse_medium parsed it
  return medium.dump();
}

// ---- quadrature ---------------------------------------------------------------------------------

namespace {

// Gauss–Legendre nodes and weights on [−1, 1], by Newton's method on P_n.
struct GaussLegendre {
  std::vector<double> x, w;
  explicit GaussLegendre(int n) {
    x.resize(n);
    w.resize(n);
    for (int i = 0; i < n; ++i) {
      double z = std::cos(std::numbers::pi * (i + 0.75) / (n + 0.5));
      double dp = 0;
      for (int iter = 0; iter < 100; ++iter) {
        double p0 = 1, p1 = z;
        for (int k = 2; k <= n; ++k) {
          const double p2 = ((2.0 * k - 1) * z * p1 - (k - 1.0) * p0) / k;
          p0 = p1;
          p1 = p2;
        }
        dp = n * (z * p1 - p0) / (z * z - 1);
        const double dz = p1 / dp;
        z -= dz;
        if (std::abs(dz) < 1e-16) break;
      }
      x[i] = z;
      w[i] = 2.0 / ((1 - z * z) * dp * dp);
    }
  }
};

const GaussLegendre& gl8() {
  static const GaussLegendre rule(8);
  return rule;
}

template <class F>
double gauss(const F& f, double a, double b) {
  const GaussLegendre& r = gl8();
  const double mid = 0.5 * (a + b), half = 0.5 * (b - a);
  double s = 0;
  for (std::size_t i = 0; i < r.x.size(); ++i) s += r.w[i] * f(mid + half * r.x[i]);
  return s * half;
}

template <class F>
double adaptive(const F& f, double a, double b, double whole, double tol, int depth) {
  const double mid = 0.5 * (a + b);
  const double left = gauss(f, a, mid), right = gauss(f, mid, b);
  if (depth <= 0 || std::abs(left + right - whole) <= tol) return left + right;
  return adaptive(f, a, mid, left, 0.5 * tol, depth - 1) +
         adaptive(f, mid, b, right, 0.5 * tol, depth - 1);
}

// ∫ₐᵇ f with panels of at most 0.1 rad, each refined adaptively to ~1e-13 of the integrand scale.
template <class F>
double integrate(const F& f, double a, double b, double scale) {
  if (a == b) return 0;
  const double sign = b > a ? 1.0 : -1.0;
  if (b < a) std::swap(a, b);
  const int panels = std::max(1, static_cast<int>(std::ceil((b - a) / 0.1)));
  const double width = (b - a) / panels;
  double sum = 0;
  for (int i = 0; i < panels; ++i) {
    const double lo = a + i * width, hi = (i + 1 == panels) ? b : lo + width;
    sum += adaptive(f, lo, hi, gauss(f, lo, hi), 1e-13 * scale * (hi - lo), 20);
  }
  return sign * sum;
}

}  // namespace

double sun_f(double u, double v) {
  LV_CHECK(u >= 0);
  return integrate([u](double xi) { return std::exp(-u * std::tan(xi)); }, 0.0, v, 1.0);
}

double phase_integral(const Phase& phase, double u, double a, double b) {
  const double scale = std::max(phase(1.0), phase(-1.0));
  return integrate(
      [&](double xi) { return phase(std::cos(2.0 * xi)) * std::exp(-u * std::tan(xi)); }, a, b,
      scale);
}

// ---- RayAirlight --------------------------------------------------------------------------------

RayAirlight::RayAirlight(const Light& light, const Medium& medium, const Ray& ray)
    : directional_(light.type == LightType::directional),
      medium_(medium),
      light_position_(light.position),
      light_direction_(light.direction),
      origin_(ray.origin),
      direction_(ray.direction),
      profiled_(light.type == LightType::spot && medium.profile.enabled()) {
  const double st = medium.extinction();
  if (directional_) {
    const Vec3d f = light.direction;
    const double k = dot(ray.direction, f);
    const double z_eye = dot(ray.origin - light.position, f) - light.near;
    dir_scale_ = medium.scattering * medium.intensity * medium.phase(-k) * std::exp(-st * z_eye);
    dir_rate_ = st * (1.0 + k);
    return;
  }
  const Vec3d to_light = light.position - ray.origin;
  s0_ = dot(to_light, ray.direction);
  h_ = length(cross(ray.direction, to_light));
  // A ray through the light itself: keep h positive (the airlight is then very large, as it is).
  h_ = std::max(h_, 1e-12 * std::max(1.0, length(to_light)));
  const double gamma = std::atan2(h_, s0_);
  xi0_ = 0.5 * gamma;
  scale_ = 2.0 * medium.scattering * medium.intensity * std::exp(-st * s0_) / h_;
}

double RayAirlight::xi(double t) const {
  if (std::isinf(t)) return 0.5 * std::numbers::pi;
  return 0.25 * std::numbers::pi + 0.5 * std::atan((t - s0_) / h_);
}

double RayAirlight::operator()(double t) const {
  if (!(t > 0)) return 0;
  if (directional_) {
    if (std::isinf(t))
      return dir_rate_ > 0 ? dir_scale_ / dir_rate_ : std::numeric_limits<double>::infinity();
    const double x = dir_rate_ * t;
    // (1 − e^(−x)) / rate, with its limit t for x → 0.
    return dir_scale_ * (std::abs(x) < 1e-8 ? t * (1 - 0.5 * x) : -std::expm1(-x) / dir_rate_);
  }
  const double u = medium_.extinction() * h_;
  if (!profiled_) return scale_ * phase_integral(medium_.phase, u, xi0_, xi(t));
  // With a spotlight profile the integrand also depends on where x(ξ) lies:
  // s(ξ) = s0 + h·tan(2ξ − π/2) = s0 − h / tan 2ξ.
  const Phase& phase = medium_.phase;
  const auto f = [&](double x) {
    const double s = s0_ - h_ / std::tan(2.0 * x);
    const Vec3d to_x = origin_ + s * direction_ - light_position_;
    const double len = length(to_x);
    const double profile = len > 0 ? medium_.profile(dot(to_x, light_direction_) / len) : 1.0;
    return phase(std::cos(2.0 * x)) * std::exp(-u * std::tan(x)) * profile;
  };
  return scale_ * integrate(f, xi0_, xi(t), std::max(phase(1.0), phase(-1.0)));
}

}  // namespace lightvol
