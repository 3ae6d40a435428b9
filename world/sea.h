#pragma once
// The sea surface (docs/MODEL.md section 18): waves from an ocean spectrum for the wind, with
// a host's wave trains laid over it, shaded by Fresnel reflection of the sky and clouds, the
// sun's glint from Cox and Munk's facet slopes, Monahan's whitecaps and the water's own
// colour. world/ only: no GL. Both renderers evaluate it through the functions below, whose
// optics (Fresnel, foam, glint) are written once in world/formulas/sea.h for the reference and
// the GL shaders alike.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "world/formulas/sea.h"

namespace nephele {

// One wave train a host sets (CIGI 3.3 Wave Control): a long-crested sine on top of the
// spectrum's sea.
struct WaveTrain {
  int id = 0;                   // the host's wave id, 0 to 255
  double height_m = 1.0;        // trough to crest
  double wavelength_m = 100.0;  // crest to crest
  double period_s = 8.0;        // 0: deep-water dispersion from the wavelength
  double direction_deg = 0.0;   // where it travels towards, clockwise from north
  double phase_deg = 0.0;       // phase offset
  bool operator==(const WaveTrain&) const = default;
};

// The sea as a scene or host sets it; it replaces the ground plane Z = 0.
struct Sea {
  glm::dvec2 wind{5.0, 0.0};    // east, north m/s at 10 m (the world's surface wind)
  double fetch_m = 0.0;         // distance the wind has blown over water; 0: fully developed
  double temperature_c = 15.0;  // surface water (the lwir channel)
  double clarity = 0.5;         // 0 turbid (coastal, green) to 1 clear (open ocean, blue)
  bool whitecaps = true;
  std::vector<WaveTrain> trains;  // by id, at most kMaxWaveTrains
  std::uint64_t seed = 1;         // the spectrum's directions and phases
  // Where the waves are laid out from, in the database: re-centring the world moves it so that
  // the waves keep their place on the Earth (MODEL.md section 13).
  glm::dvec2 origin_m{0.0};
  bool operator==(const Sea&) const = default;
};
inline constexpr int kMaxWaveTrains = 8;

// One sine of the surface (deep-water linear waves), its phase modulated slowly in space so
// that a finite sum does not repeat (MODEL.md section 18): height
// a cos(k . x - omega t + phase + kWaveModulation sin(q . x + psi)).
struct WaveComponent {
  glm::dvec2 k{0.0};  // wave vector, rad/m, pointing where it travels
  double amplitude = 0.0, omega = 0.0, phase = 0.0;
  glm::dvec2 q{0.0};  // the modulation's wave vector (0 for a host's wave train)
  double psi = 0.0;
};
inline constexpr double kWaveModulation = 2.5;  // radians

// The surface at a point, its waves shorter than the footprint left out (their slopes join the
// unresolved variance, so that a pixel's glint spreads as the sea's does).
struct SeaSample {
  double height = 0.0;                // resolved elevation, m
  glm::dvec2 slope{0.0};              // resolved dz/dx, dz/dy
  double unresolved_slope_var = 0.0;  // sigma^2 of the slopes left to Cox-Munk's distribution
  double unresolved_height_var = 0.0;
  double resolved_slope_var = 0.0;  // of the drawn sines' slopes, the share resolved here
};

// Spectrum, discretised once per sea: kSeaComponents sines (plus the host's trains).
inline constexpr int kSeaComponents = 64;
class SeaSurface {
 public:
  // `components`: how many sines stand for the spectrum (the knob sea_waves).
  explicit SeaSurface(const Sea& sea, int components = kSeaComponents);

  double windSpeed() const { return wind_speed_; }
  // Cox and Munk (1954), clean surface: total mean square slope 0.003 + 5.12e-3 W.
  double slopeVariance() const { return slope_var_; }
  double heightVariance() const { return height_var_; }
  double significantHeight() const { return 4.0 * std::sqrt(height_var_); }
  double peakOmega() const { return peak_omega_; }
  // Monahan and O'Muircheartaigh (1980): W = 3.84e-6 U^3.41, at most 1; 0 without whitecaps.
  double whitecapFraction() const { return whitecap_fraction_; }
  // The drawn sines' slope variance, sum of a^2 k^2 / 2.
  double drawnSlopeVariance() const { return drawn_slope_var_; }
  // The squared slope that a fraction whitecapFraction() of the fully resolved surface exceeds:
  // a quantile of 65,536 samples (about 0.3 s), taken on first use and kept.
  double foamSteepness() const;
  const std::vector<WaveComponent>& components() const { return components_; }
  // The same waves laid out from `origin` (Sea::origin_m) in place of this one's: the phases
  // move by the wave vectors times the step, and foamSteepness, taken where the waves are laid
  // out from, is shared.
  SeaSurface movedTo(glm::dvec2 origin) const;

  // At world X, Y at time t, seen with a footprint of `footprint_m` (metres a pixel covers).
  SeaSample sample(glm::dvec2 xy, double time_s, double footprint_m) const;

 private:
  double wind_speed_ = 0.0, slope_var_ = 0.0, height_var_ = 0.0, peak_omega_ = 0.0;
  double whitecap_fraction_ = 0.0, drawn_slope_var_ = 0.0;
  std::uint64_t seed_ = 1;
  glm::dvec2 origin_{0.0};
  // foamSteepness, once computed (shared by copies, which draw the same surface).
  struct Lazy {
    std::once_flag once;
    double value = 0.0;
  };
  std::shared_ptr<Lazy> foam_steepness_ = std::make_shared<Lazy>();
  std::vector<WaveComponent> components_;  // longest first
};

// The spectrum, Cox-Munk's slopes and Monahan's whitecaps take the wind up to this speed: a
// fully developed sea at 40 m/s has a significant height of 34 m, beyond any observed (a
// stronger legal wind draws that sea).
inline constexpr double kMaxSeaWind = 40.0;

// A component's weight for a footprint: 1 while its wavelength is at least 8 footprints, 0 at
// 4 or fewer, linear between (what a pixel can show of it).
double waveResolved(double wavelength_m, double footprint_m);

// Unpolarised Fresnel reflectance of a water surface for the cosine of the incidence angle,
// refractive index n (1.34 visible, 1.2 thermal infrared).
double fresnelWater(double cos_incidence, double n = 1.34);

// The water's diffuse reflectance below the surface for its clarity (linear RGB).
glm::dvec3 waterBodyColour(double clarity);

// The effective reflectance of whitecap foam (Koepke 1984): world/formulas/sea.h.
using formulas::kFoamReflectance;

// The share of a point covered by foam (MODEL.md section 18): where the surface is resolved,
// where it is steepest, its squared slope above `foam_steepness` (what a fraction W of the
// fully resolved surface exceeds), the edges softened over the unresolved slopes' variance;
// where it is not, W. The two blend by the share of the drawn slope variance resolved.
double foamShare(double whitecap_fraction, double foam_steepness, double steepness,
                 double var_drawn, double var_unresolved);

// What the sea shows along unit view ray `d` meeting it at a point: the light a renderer
// composes. Radiances in the renderers' units (a white diffuser facing the sun has 1).
struct SeaShading {
  glm::dvec3 reflect_dir{0.0, 0.0, 1.0};  // where the sky and clouds are seen in it
  double fresnel = 0.0;                   // weight of the reflected radiance
  glm::dvec3 body_and_foam{0.0};          // water colour and foam, lit (times sunlight share)
  glm::dvec3 glint{0.0};                  // sun glint (times sunlight share)
  double foam = 0.0;                      // foam share
  double cos_incidence = 1.0;             // of the ray on the resolved surface's facet
};
// `sunlight`: the share of the sun reaching the point (cloud shadows), `sun` unit towards it.
SeaShading shadeSea(const SeaSurface& surface, const Sea& sea, const SeaSample& s, glm::dvec3 d,
                    glm::dvec3 sun, glm::dvec3 sun_colour, double sunlight);

// Cox-Munk glint radiance for a unit irradiance per pi (the renderers' sun): F p(slopes) /
// (4 mu_v mu_n^4), the facet normal that mirrors `d` to `sun` taken relative to `normal` (the
// resolved surface's), slopes distributed with variance `slope_var` (isotropic).
double glintRadiance(glm::dvec3 d, glm::dvec3 sun, glm::dvec3 normal, double slope_var);

// The sea's thermal emissivity along a ray meeting its surface at `cos_incidence`: 1 - F.
inline double seaEmissivity(double cos_incidence) {
  return 1.0 - fresnelWater(cos_incidence, 1.2);
}

// The angle a pixel spans, radians, for a camera's vertical field of view and height in pixels.
inline double seaPixelAngle(double vfov_deg, int height_px) {
  return 2.0 * std::tan(0.5 * vfov_deg * 3.141592653589793 / 180.0) / std::max(height_px, 1);
}

// The metres per pixel along a ray below the horizon (world/formulas/sea.h).
using formulas::seaFootprint;

}  // namespace nephele
