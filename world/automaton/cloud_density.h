#pragma once
// From automaton cells to light (MODEL.md section 6): metaball density, sunlight through it, and
// the phase functions of single scattering. Grid frame: metres from the grid's lower corner,
// cell (i, j, k) centred at ((i, j, k) + 0.5) * cell size.
#include <cmath>
#include <vector>

#include <glm/glm.hpp>

#include "world/automaton/cellular_automaton.h"

namespace nephele {

inline constexpr double kCloudExtinctionPerMetre =
    16.33e-3;                                        // Ex for density 1 (MODEL.md section 6)
inline constexpr double kMetaballRadiusCells = 2.0;  // R = 2 l (MODEL.md section 6 default)
// Asymmetry of cloud droplets' scattering for diffuse light (MODEL.md section 6, sky light).
inline constexpr double kDiffuseAsymmetry = 0.85;

// The share of diffuse light a non-absorbing cloud layer of optical depth tau lets through
// (two-stream: 1 / (1 + 3/4 (1 - g) tau); MODEL.md section 6, sky light). 1 at tau = 0,
// falling as 1 / tau, never to 0.
inline double diffuseTransmittance(double tau) {
  return 1.0 / (1.0 + 0.75 * (1.0 - kDiffuseAsymmetry) * tau);
}

// The metaball field f(r) = -4/9 a^6 + 17/9 a^4 - 22/9 a^2 + 1, a = r / R; 0 beyond R.
double metaballField(double r, double radius);

// q(cell): the mean of cld over the cells within R of the cell (cells outside read 0).
std::vector<float> cellMeans(const CellularAutomaton& automaton,
                             double radius_cells = kMetaballRadiusCells);

// rho(x) = sum over cells within R of x of q(cell) f(|x - x_cell|), x in the grid frame.
double metaballDensity(const std::vector<float>& means, GridSize size, double cell_size,
                       glm::dvec3 x, double radius_cells = kMetaballRadiusCells);

// Density and sunlight sampled on a lattice: `samples_per_cell` samples per cell edge, aligned
// with the cell centres and reaching R beyond the outermost ones, so that the density is 0
// outside the lattice.
struct DensityLattice {
  glm::ivec3 dims{0};
  double spacing = 0.0;         // metres between samples
  glm::dvec3 origin{0.0};       // grid-frame position of sample (0, 0, 0)
  std::vector<float> density;   // x fastest
  std::vector<float> sunlight;  // transmittance towards the sun, exp(-tau)
  std::vector<float> skylight;  // share of the sky light reaching the sample (sweepSkylight)
  // Samples bounding every non-zero density sample, widened by one: the trilinear density is
  // 0 outside them (lo > hi when the cloud is empty).
  glm::ivec3 occupied_lo{0}, occupied_hi{-1};

  std::size_t index(int x, int y, int z) const {
    return (std::size_t(z) * dims.y + y) * dims.x + x;
  }
  glm::dvec3 position(int x, int y, int z) const { return origin + glm::dvec3(x, y, z) * spacing; }
  glm::dvec3 extent() const { return glm::dvec3(dims - 1) * spacing; }
  // Trilinear density at a grid-frame point; 0 outside.
  double densityAt(glm::dvec3 x) const;
};

// The exact metaball density at every lattice sample: q splatted through a fixed kernel table,
// with its skylight (sweepSkylight); sunlight is left at 1 for sweepSunlight.
DensityLattice densityLattice(const std::vector<float>& means, GridSize size, double cell_size,
                              int samples_per_cell);

// Fills `lattice.sunlight` by one sweep from the sun's side: each sample's transmittance is that
// of the point one slice nearer the sun (bilinear on that slice) times the exact exponential
// of the segment between them, with the density linear along it. O(samples).
void sweepSunlight(DensityLattice& lattice, glm::dvec3 to_sun,
                   double extinction_per_m = kCloudExtinctionPerMetre);
// Fills `lattice.skylight`: how much of the sky light reaches each sample through the cloud
// straight above it, diffuseTransmittance of that column's optical depth (MODEL.md section 6,
// sky light). A vertical column needs no interpolation: exact at every sample.
void sweepSkylight(DensityLattice& lattice, double extinction_per_m = kCloudExtinctionPerMetre);

// Transmittance of a segment whose density runs linearly from rho_a to rho_b: exact, and
// stays in [0, 1] however thick the segment.
inline double segmentTransmittance(double rho_a, double rho_b, double length,
                                   double extinction_per_m = kCloudExtinctionPerMetre) {
  return std::exp(-extinction_per_m * 0.5 * (rho_a + rho_b) * length);
}

enum class PhaseFunction { kRayleigh, kCornetteShanks };

// Both integrate to 4 pi over the sphere (mean 1). cos_theta is the cosine of the scattering
// angle between the sunlight's direction of travel and the scattered ray's.
double rayleighPhase(double cos_theta);                  // 3/4 (1 + cos^2)
double cornetteShanksPhase(double cos_theta, double g);  // Shen eq. 11
double cornetteShanksAsymmetry(double u);                // Shen eq. 12-13, g(u)

}  // namespace nephele
