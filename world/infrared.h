#pragma once
// A long-wave infrared band (docs/MODEL.md section 12): what a thermal imager sees of the same
// world. Everything radiates as a grey body at its temperature; a cloud's emissivity is its
// opacity (Gardner's 1 - TR, or the volume's 1 - transmittance), so thin cloud shows what is
// behind it; cloud temperature follows the ISA lapse rate with altitude; the clear sky is a
// cold atmosphere whose emissivity rises toward the horizon with the air mass.
#include <vector>

namespace nephele {

struct InfraredModel {
  double band_lo_um = 8.0, band_hi_um = 12.0;  // the band, micrometres
  int band_steps = 16;                         // midpoint rule over the band (a knob)
  double surface_air_k = 288.15;               // air at Z = 0 (ISA sea level)
  double ground_k = 288.15;                    // ground or sea surface
  double ground_emissivity = 0.98;
  double sky_zenith_emissivity = 0.25;      // clear sky straight up, in this band
  double target_k = 300.0;                  // every target unless target_temperatures says
  std::vector<double> target_temperatures;  // per scene target, kelvin
};

// ISA: surface_air_k - 6.5 K/km up to 11 km, constant above.
double airTemperature(const InfraredModel& model, double altitude_m);
// Black-body radiance integrated over the band, W m^-2 sr^-1.
double bandRadiance(const InfraredModel& model, double temperature_k);
// The temperature of a black body giving `radiance` in the band (inverse of bandRadiance).
double brightnessTemperature(const InfraredModel& model, double radiance);
// Clear sky along a ray at `elevation_rad` (> 0) from a camera at `altitude_m`: emissivity
// 1 - (1 - e_zenith)^(1 / sin elevation) times the black body at the camera's air temperature.
double clearSkyRadiance(const InfraredModel& model, double elevation_rad, double altitude_m);
double targetTemperature(const InfraredModel& model, int target);

// bandRadiance tabulated from 100 K to 400 K in steps of 1/8 K, for converting whole images:
// radiance by linear interpolation, brightness temperature by binary search and
// interpolation (outside the table: the exact functions).
class BandTable {
 public:
  explicit BandTable(const InfraredModel& model);
  double temperature(double radiance) const;

 private:
  InfraredModel model_;
  std::vector<double> radiance_;  // at 100 + i / 8 K
};

}  // namespace nephele
