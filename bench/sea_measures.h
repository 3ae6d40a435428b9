#pragma once
// Measurements of the sea's surface (MODEL.md section 18) against the works it follows, shared
// by sea_bench (which prints them) and tests/sea_test.cpp (which bounds them): each computed
// from samples of the drawn surface, never from its own formulas.
#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include "world/counter_random.h"
#include "world/sea.h"

namespace nephele::sea_measures {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kG = 9.81;

// In-place radix-2 FFT (size a power of 2).
inline void fft(std::vector<std::complex<double>>& a) {
  const std::size_t n = a.size();
  for (std::size_t i = 1, j = 0; i < n; ++i) {
    std::size_t bit = n >> 1;
    for (; j & bit; bit >>= 1) j ^= bit;
    j ^= bit;
    if (i < j) std::swap(a[i], a[j]);
  }
  for (std::size_t len = 2; len <= n; len <<= 1) {
    const std::complex<double> w = std::polar(1.0, -2.0 * kPi / double(len));
    for (std::size_t i = 0; i < n; i += len) {
      std::complex<double> u(1.0);
      for (std::size_t k = 0; k < len / 2; ++k, u *= w) {
        const std::complex<double> x = a[i + k], y = a[i + k + len / 2] * u;
        a[i + k] = x + y;
        a[i + k + len / 2] = x - y;
      }
    }
  }
}

// Least-squares slope of y against x.
inline double fitSlope(const std::vector<double>& x, const std::vector<double>& y) {
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < x.size(); ++i) mx += x[i], my += y[i];
  mx /= double(x.size()), my /= double(x.size());
  double sxy = 0, sxx = 0;
  for (std::size_t i = 0; i < x.size(); ++i)
    sxy += (x[i] - mx) * (y[i] - my), sxx += (x[i] - mx) * (x[i] - mx);
  return sxy / sxx;
}

// Pierson and Moskowitz's spectrum for wind `speed`, m^2 s.
inline double piersonMoskowitz(double w, double speed) {
  const double wp = 0.877 * kG / speed;
  return 8.1e-3 * kG * kG / std::pow(w, 5) * std::exp(-1.25 * std::pow(wp / w, 4));
}

struct SpectrumFit {
  // Of the log band density against log omega over [1.5, 4] w_p, to the shortest sine drawn
  // (NaN with fewer than three bands there).
  double measured_slope = 0.0;
  double expected_slope = 0.0;  // Pierson-Moskowitz's over the same bands
  double energy_ratio = 0.0;    // height variance over the spectrum's from 0.7 w_p up
};

// The height at the origin sampled every 0.1 s for 55 minutes, Hann-windowed, its periodogram
// summed in bands a factor 1.25 wide; a fully developed sea of wind `speed`.
inline SpectrumFit measureSpectrum(const SeaSurface& surface, double speed) {
  const double dt = 0.1;
  const std::size_t n = 1 << 15;
  std::vector<std::complex<double>> series(n);
  double variance = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double h = surface.sample({0.0, 0.0}, double(i) * dt, 0.0).height;
    variance += h * h / double(n);
    series[i] = h * (0.5 - 0.5 * std::cos(2.0 * kPi * double(i) / double(n)));
  }
  fft(series);
  const double wp = 0.877 * kG / speed;
  SpectrumFit fit;
  double expected = 0.0;
  const double hi = surface.components().back().omega;
  for (double w = 0.7 * wp; w < hi; w += 1e-4) expected += piersonMoskowitz(w, speed) * 1e-4;
  fit.energy_ratio = variance / expected;
  std::vector<double> lx, ly, lpm;
  const double dw = 2.0 * kPi / (double(n) * dt);
  // Up to 4 w_p, or the shortest sine drawn (shorter waves are left to Cox-Munk's facets).
  const double top = std::min(4.0 * wp * 1.01, hi);
  for (double lo = 1.5 * wp; lo * 1.25 <= top; lo *= 1.25) {
    double energy = 0.0, exact = 0.0;
    for (std::size_t k = std::size_t(std::ceil(lo / dw)); double(k) * dw < lo * 1.25; ++k)
      energy += std::norm(series[k]);
    for (double w = lo; w < lo * 1.25; w += 1e-4) exact += piersonMoskowitz(w, speed) * 1e-4;
    lx.push_back(std::log(lo * std::sqrt(1.25)));
    ly.push_back(std::log(energy / (lo * 0.25)));
    lpm.push_back(std::log(exact / (lo * 0.25)));
  }
  if (lx.size() < 3) return {std::nan(""), std::nan(""), fit.energy_ratio};
  fit.measured_slope = fitSlope(lx, ly);
  fit.expected_slope = fitSlope(lx, lpm);
  return fit;
}

// The largest |autocorrelation| of the height along a 65,536-sample line in direction `dir`,
// at lags from three peak wavelengths to 10 km: 1 at a tile's period, under 0.3 asked.
inline double repetition(const SeaSurface& surface, glm::dvec2 dir) {
  const double peak_wavelength = 2.0 * kPi * kG / (surface.peakOmega() * surface.peakOmega());
  const std::size_t n = 1 << 16;
  const double step = std::max(0.25, peak_wavelength / 40.0);
  std::vector<std::complex<double>> line(2 * n);
  for (std::size_t i = 0; i < n; ++i)
    line[i] = surface.sample(double(i) * step * dir, 0.0, 0.0).height;
  fft(line);
  for (auto& v : line) v = std::norm(v);
  fft(line);  // the autocorrelation (for real input, symmetric)
  const double zero = line[0].real();
  double worst = 0.0;
  for (std::size_t lag = std::size_t(3.0 * peak_wavelength / step);
       double(lag) * step <= 10000.0 && lag < n / 2; ++lag)
    worst = std::max(worst, std::abs(line[lag].real()) / (zero * double(n - lag) / double(n)));
  return worst;
}

// The mean of f(sample) over `samples` points of a `side` metre square, the surface seen at full
// resolution at time 0; the points drawn by counter-based randomness on `stream`.
template <typename F>
double meanOverSquare(const SeaSurface& surface, int samples, double side, std::uint64_t stream,
                      F f) {
  double mean = 0.0;
  for (int i = 0; i < samples; ++i) {
    const glm::dvec2 xy(side * unitFromBits(hashCounters(stream, i, 0)),
                        side * unitFromBits(hashCounters(stream, i, 1)));
    mean += f(surface.sample(xy, 0.0, 0.0)) / samples;
  }
  return mean;
}

// Cox and Munk (1954): the glint radiance per unit sun irradiance, F p / (4 mu_v cos^4 beta),
// slopes normal with mean square 0.003 + 5.12e-3 W, for the view that a facet tilted by beta
// towards the viewer mirrors into `sun` (unit); and the drawn surface's glint for that view,
// the mean over 20,000 points of a 5 km square. Their ratio.
inline double glintRatio(const SeaSurface& surface, double speed, double tan_beta, glm::dvec3 sun) {
  const double s2 = 0.003 + 5.12e-3 * speed;
  const double beta = std::atan(tan_beta);
  const glm::dvec3 facet(0.0, -std::sin(beta), std::cos(beta));
  const glm::dvec3 d = -glm::reflect(-sun, facet);  // from the eye to the sea
  const glm::dvec3 v = -d;
  const double predicted = fresnelWater(glm::dot(v, facet)) * std::exp(-tan_beta * tan_beta / s2) /
                           (4.0 * s2 * v.z * std::pow(std::cos(beta), 4));
  const double mean = meanOverSquare(surface, 20000, 5000.0, 7, [&](const SeaSample& s) {
    const glm::dvec3 n = glm::normalize(glm::dvec3(-s.slope.x, -s.slope.y, 1.0));
    return glintRadiance(d, sun, n, s.unresolved_slope_var);
  });
  return mean / predicted;
}

// The mean foam share over 100,000 points of a 40 km square, seen at full resolution.
inline double meanFoam(const SeaSurface& surface) {
  return meanOverSquare(surface, 100000, 40000.0, 9, [&](const SeaSample& s) {
    return foamShare(surface.whitecapFraction(), surface.foamSteepness(),
                     glm::dot(s.slope, s.slope), surface.drawnSlopeVariance(),
                     surface.drawnSlopeVariance() - s.resolved_slope_var);
  });
}

}  // namespace nephele::sea_measures
