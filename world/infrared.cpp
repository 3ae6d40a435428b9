#include "world/infrared.h"

#include <algorithm>
#include <cmath>

namespace nephele {

double airTemperature(const InfraredModel& model, double altitude_m) {
  return model.surface_air_k - 0.0065 * std::clamp(altitude_m, 0.0, 11000.0);
}

double bandRadiance(const InfraredModel& model, double temperature_k) {
  // Planck's law per wavelength, B = 2 h c^2 / l^5 / (exp(h c / (l k T)) - 1), in
  // W m^-2 sr^-1 m^-1, summed by the midpoint rule.
  constexpr double h = 6.62607015e-34, c = 2.99792458e8, k = 1.380649e-23;
  if (!(temperature_k > 0.0)) return 0.0;
  const int n = std::max(1, model.band_steps);
  const double lo = model.band_lo_um * 1e-6, hi = model.band_hi_um * 1e-6;
  const double step = (hi - lo) / n;
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const double l = lo + (i + 0.5) * step;
    sum += 2.0 * h * c * c / std::pow(l, 5) / std::expm1(h * c / (l * k * temperature_k));
  }
  return sum * step;
}

double brightnessTemperature(const InfraredModel& model, double radiance) {
  if (!(radiance > 0.0)) return 0.0;
  // bandRadiance rises monotonically with temperature: bisection over 1 K to 5000 K.
  double lo = 1.0, hi = 5000.0;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (bandRadiance(model, mid) < radiance ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double clearSkyRadiance(const InfraredModel& model, double elevation_rad, double altitude_m) {
  const double s = std::max(std::sin(elevation_rad), 0.01);
  const double emissivity = 1.0 - std::pow(1.0 - model.sky_zenith_emissivity, 1.0 / s);
  return emissivity * bandRadiance(model, airTemperature(model, altitude_m));
}

double targetTemperature(const InfraredModel& model, int target) {
  return target >= 0 && std::size_t(target) < model.target_temperatures.size()
             ? model.target_temperatures[std::size_t(target)]
             : model.target_k;
}

BandTable::BandTable(const InfraredModel& model) : model_(model) {
  for (int i = 0; i <= 300 * 8; ++i) radiance_.push_back(bandRadiance(model, 100.0 + i / 8.0));
}

double BandTable::temperature(double radiance) const {
  if (!(radiance > radiance_.front()) || !(radiance < radiance_.back()))
    return brightnessTemperature(model_, radiance);
  const auto above = std::upper_bound(radiance_.begin(), radiance_.end(), radiance);
  const std::size_t i = std::size_t(above - radiance_.begin()) - 1;
  const double f = (radiance - radiance_[i]) / (radiance_[i + 1] - radiance_[i]);
  return 100.0 + (double(i) + f) / 8.0;
}

}  // namespace nephele
