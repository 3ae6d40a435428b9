#include "world/sea.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "world/counter_random.h"
#include "world/formations/cloud_shadow.h"

namespace nephele {
namespace {

constexpr double kG = 9.81;
constexpr double kPi = std::numbers::pi;
// The shortest wave drawn: shorter ones are capillary-gravity ripples, left to Cox-Munk.
constexpr double kShortestWave = 0.5;

// The omnidirectional frequency spectrum S(omega), m^2 s (MODEL.md section 18): JONSWAP for a
// fetch-limited sea, Pierson-Moskowitz when the fetch is long enough to be fully developed.
struct Spectrum {
  double alpha = 8.1e-3, peak = 0.0, gamma = 1.0;
  double operator()(double w) const {
    const double r = peak / w;
    double s = alpha * kG * kG / std::pow(w, 5.0) * std::exp(-1.25 * r * r * r * r);
    if (gamma > 1.0) {
      const double sigma = w <= peak ? 0.07 : 0.09, x = (w - peak) / (sigma * peak);
      s *= std::pow(gamma, std::exp(-0.5 * x * x));
    }
    return s;
  }
};

Spectrum spectrumFor(double wind, double fetch) {
  Spectrum s;
  s.peak = 0.877 * kG / wind;  // Pierson and Moskowitz (1964)
  if (fetch > 0.0) {
    // Hasselmann et al. (1973): alpha = 0.076 x^-0.22, omega_p = 22 (g^2 / (U F))^(1/3).
    const double x = kG * fetch / (wind * wind);
    const double peak = 22.0 * std::cbrt(kG * kG / (wind * fetch));
    if (peak > s.peak) s = {0.076 * std::pow(x, -0.22), peak, 3.3};
  }
  return s;
}

// The inverse of the cos^2 spreading's distribution, D(theta) = (2 / pi) cos^2 theta on
// [-pi/2, pi/2], CDF (theta + sin theta cos theta) / pi + 1/2, by Newton's method.
double spreadAngle(double u) {
  double theta = (u - 0.5) * kPi * 0.5;
  for (int i = 0; i < 20; ++i) {
    const double c = std::cos(theta);
    const double f = (theta + std::sin(theta) * c) / kPi + 0.5 - u;
    theta -= f / std::max(2.0 * c * c / kPi, 1e-9);
    theta = std::clamp(theta, -0.5 * kPi, 0.5 * kPi);
  }
  return theta;
}

}  // namespace

double waveResolved(double wavelength_m, double footprint_m) {
  if (!(footprint_m > 0.0)) return 1.0;
  return formulas::waveResolved(wavelength_m, footprint_m);
}

SeaSurface::SeaSurface(const Sea& sea, int count) {
  count = std::max(count, 1);
  const double blowing = glm::length(sea.wind);
  wind_speed_ = std::min(blowing, kMaxSeaWind);
  slope_var_ = 0.003 + 5.12e-3 * wind_speed_;  // Cox and Munk (1954), clean surface
  whitecap_fraction_ = sea.whitecaps ? std::min(1.0, 3.84e-6 * std::pow(wind_speed_, 3.41)) : 0.0;
  if (wind_speed_ >= 0.5) {
    const glm::dvec2 along = sea.wind / blowing;
    const Spectrum spectrum = spectrumFor(wind_speed_, sea.fetch_m);
    peak_omega_ = spectrum.peak;
    const double lo = 0.7 * spectrum.peak;
    const double hi = std::max(std::sqrt(kG * 2.0 * kPi / kShortestWave), 3.0 * spectrum.peak);
    const double step = std::log(hi / lo) / count;
    // Directions stratified over the spreading, in an order shuffled by the seed, so that
    // neighbouring frequencies do not travel alike.
    std::vector<int> order(std::size_t(count), 0);
    for (int i = 0; i < count; ++i) order[std::size_t(i)] = i;
    for (int i = count - 1; i > 0; --i)
      std::swap(order[std::size_t(i)], order[hashCounters(sea.seed, 1, i) % std::uint64_t(i + 1)]);
    double budget = formulas::kResolvedSlopeShare * slope_var_;
    for (int i = 0; i < count; ++i) {
      const double jitter = unitFromBits(hashCounters(sea.seed, 2, i));
      const double w = lo * std::exp((i + jitter) * step);
      const double dw = lo * (std::exp((i + 1) * step) - std::exp(i * step));
      const double a = std::sqrt(2.0 * spectrum(w) * dw);
      const double k = w * w / kG;
      const double slope_var = 0.5 * (a * k) * (a * k);
      if (slope_var > budget) break;  // the rest are left to the facets' distribution
      budget -= slope_var;
      const double u = (order[std::size_t(i)] + unitFromBits(hashCounters(sea.seed, 3, i))) / count;
      const double theta = spreadAngle(u);
      const glm::dvec2 dir =
          std::cos(theta) * along + std::sin(theta) * glm::dvec2(-along.y, along.x);
      // The modulation: a twentieth of the wave number, give or take 30 %, in any direction.
      const double turn = 2.0 * kPi * unitFromBits(hashCounters(sea.seed, 6, i));
      const double q = k * (0.035 + 0.03 * unitFromBits(hashCounters(sea.seed, 7, i)));
      components_.push_back({k * dir, a, w, 2.0 * kPi * unitFromBits(hashCounters(sea.seed, 4, i)),
                             q * glm::dvec2(std::cos(turn), std::sin(turn)),
                             2.0 * kPi * unitFromBits(hashCounters(sea.seed, 8, i))});
    }
  }
  for (const WaveTrain& t : sea.trains) {
    const double k = 2.0 * kPi / t.wavelength_m;
    const double heading = t.direction_deg * kPi / 180.0;
    const double omega = t.period_s > 0.0 ? 2.0 * kPi / t.period_s : std::sqrt(kG * k);
    components_.push_back({k * glm::dvec2(std::sin(heading), std::cos(heading)), 0.5 * t.height_m,
                           omega, t.phase_deg * kPi / 180.0, glm::dvec2(0.0), 0.0});
  }
  std::stable_sort(components_.begin(), components_.end(),
                   [](const WaveComponent& a, const WaveComponent& b) {
                     return glm::length(a.k) < glm::length(b.k);
                   });
  for (const WaveComponent& c : components_) {
    const double k = glm::length(c.k);
    height_var_ += 0.5 * c.amplitude * c.amplitude;
    drawn_slope_var_ += 0.5 * c.amplitude * c.amplitude * k * k;
  }
  seed_ = sea.seed;
  *this = movedTo(sea.origin_m);
}

SeaSurface SeaSurface::movedTo(glm::dvec2 origin) const {
  SeaSurface out = *this;
  const glm::dvec2 step = origin - origin_;
  // Each height term a cos(k.(x - o) - w t + phase + M sin(q.(x - o) + psi)) keeps its form
  // with the offsets folded into its phases, reduced to keep them small.
  for (WaveComponent& c : out.components_) {
    c.phase = std::remainder(c.phase - glm::dot(c.k, step), 2.0 * kPi);
    c.psi = std::remainder(c.psi - glm::dot(c.q, step), 2.0 * kPi);
  }
  out.origin_ = origin;
  return out;
}

double SeaSurface::foamSteepness() const {
  Lazy& lazy = *foam_steepness_;
  std::call_once(lazy.once, [&] {
    if (!(whitecap_fraction_ > 0.0 && whitecap_fraction_ < 1.0) || components_.empty()) return;
    // The fully resolved squared slopes' quantile, from points scattered over 400 peak
    // wavelengths.
    const double reach = 400.0 * 2.0 * kPi / glm::length(components_.front().k);
    std::vector<double> steepness(65536);
    for (std::size_t i = 0; i < steepness.size(); ++i) {
      const glm::dvec2 slope =
          sample(origin_ + reach * glm::dvec2(unitFromBits(hashCounters(seed_, 5, i, 0)),
                                              unitFromBits(hashCounters(seed_, 5, i, 1))),
                 0.0, 0.0)
              .slope;
      steepness[i] = glm::dot(slope, slope);
    }
    std::sort(steepness.begin(), steepness.end());
    const auto at = std::min(steepness.size() - 1,
                             std::size_t((1.0 - whitecap_fraction_) * double(steepness.size())));
    lazy.value = steepness[at];
  });
  return lazy.value;
}

SeaSample SeaSurface::sample(glm::dvec2 xy, double time_s, double footprint_m) const {
  SeaSample s;
  double resolved_slope_var = 0.0, resolved_height_var = 0.0;
  for (const WaveComponent& c : components_) {  // longest first
    const double k = glm::length(c.k);
    const double w = waveResolved(2.0 * kPi / k, footprint_m);
    if (w <= 0.0) break;  // and every shorter one
    const double wobble = glm::dot(c.q, xy) + c.psi;
    const double phase =
        glm::dot(c.k, xy) - c.omega * time_s + c.phase + kWaveModulation * std::sin(wobble);
    s.height += w * c.amplitude * std::cos(phase);
    s.slope -= formulas::waveSlope(w, c.amplitude, std::sin(phase), c.k, kWaveModulation,
                                   std::cos(wobble), c.q);
    const double height_var = formulas::waveHeightVariance(w, c.amplitude);
    resolved_height_var += height_var;
    resolved_slope_var += height_var * k * k;
  }
  s.unresolved_height_var = std::max(height_var_ - resolved_height_var, 0.0);
  s.resolved_slope_var = resolved_slope_var;
  s.unresolved_slope_var = formulas::unresolvedSlopeVariance(slope_var_, resolved_slope_var);
  return s;
}

double fresnelWater(double cos_incidence, double n) {
  return formulas::fresnelWater(cos_incidence, n);
}

glm::dvec3 waterBodyColour(double clarity) {
  // Irradiance reflectance just below the surface: coastal water scatters green from its
  // sediment and plankton, clear ocean water reflects little but blue.
  const glm::dvec3 turbid(0.012, 0.030, 0.018), clear(0.002, 0.008, 0.035);
  return glm::mix(turbid, clear, std::clamp(clarity, 0.0, 1.0));
}

double foamShare(double whitecap_fraction, double foam_steepness, double steepness,
                 double var_total, double var_unresolved) {
  return formulas::foamShare(whitecap_fraction, foam_steepness, steepness, var_total,
                             var_unresolved);
}

double glintRadiance(glm::dvec3 d, glm::dvec3 sun, glm::dvec3 normal, double slope_var) {
  return formulas::glintRadiance(d, sun, normal, slope_var);
}

SeaShading shadeSea(const SeaSurface& surface, const Sea& sea, const SeaSample& s, glm::dvec3 d,
                    glm::dvec3 sun, glm::dvec3 sun_colour, double sunlight) {
  SeaShading out;
  const glm::dvec3 n = formulas::seaNormal(s.slope);
  const double cos_i = formulas::seaIncidence(d, n);
  out.cos_incidence = cos_i;
  out.reflect_dir = formulas::mirroredRay(d, n, cos_i);
  out.foam =
      foamShare(surface.whitecapFraction(), surface.foamSteepness(), glm::dot(s.slope, s.slope),
                surface.drawnSlopeVariance(), surface.drawnSlopeVariance() - s.resolved_slope_var);
  const double fresnel = fresnelWater(cos_i);
  out.fresnel = (1.0 - out.foam) * fresnel;
  // Diffuse light on the surface, per pi: the sun's and the sky's (the ground's share in shadow).
  const double diffuse = std::max(sun.z, 0.0) * groundLight(sunlight);
  out.body_and_foam = formulas::seaBodyAndFoam(
      diffuse, out.foam, fresnel, sun_colour * waterBodyColour(sea.clarity), sun_colour);
  if (sun.z > 0.0 && sunlight > 0.0)
    out.glint =
        (1.0 - out.foam) * sunlight * glintRadiance(d, sun, n, s.unresolved_slope_var) * sun_colour;
  return out;
}

}  // namespace nephele
