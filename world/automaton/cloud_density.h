#pragma once
// From automaton cells to light (MODEL.md section 6): metaball density, sunlight through it, and
// the phase functions of single scattering. Grid frame: metres from the grid's lower corner,
// cell (i, j, k) centred at ((i, j, k) + 0.5) * cell size.
#include <algorithm>
#include <cmath>
#include <vector>

#include <glm/glm.hpp>

#include "world/automaton/cellular_automaton.h"
#include "world/formulas/heap.h"
#include "world/formulas/volume.h"

namespace nephele {

inline constexpr double kCloudExtinctionPerMetre =
    16.33e-3;                                        // Ex for density 1 (MODEL.md section 6)
inline constexpr double kMetaballRadiusCells = 2.0;  // R = 2 l (MODEL.md section 6 default)
// Asymmetry of cloud droplets' scattering for diffuse light (MODEL.md section 6, sky light).
using formulas::kDiffuseAsymmetry;

// The share of diffuse light a non-absorbing cloud layer of optical depth tau lets through
// (two-stream: 1 / (1 + 3/4 (1 - g) tau); MODEL.md section 6, sky light). 1 at tau = 0,
// falling as 1 / tau, never to 0.
inline double diffuseTransmittance(double tau) {
  return formulas::diffuseTransmittance(tau, kDiffuseAsymmetry);
}

// The sunlight at a point in all, scattered or not, per unit of the sun's (MODEL.md section 6,
// multiple scattering): the two-stream sum of the fluxes along and against the sun's ray in a
// non-absorbing slab, the ray's own path through the cloud, tau_sun the optical depth from the
// point towards the sun and tau_away that on out of the far side:
// (1 + 2 k tau_away) / (1 + k (tau_sun + tau_away)), k = 3/4 (1 - g). Near 2 on a thick sunlit
// face (the beam and the light scattered back out), diffuseTransmittance(tau_sun) on the far
// face; finite and in (0, 2) for finite depths.
inline double diffuseSunlight(double tau_sun, double tau_away) {
  const double k = 0.75 * (1.0 - kDiffuseAsymmetry);
  return (1.0 + 2.0 * k * tau_away) / (1.0 + k * (tau_sun + tau_away));
}

// The light a point scatters towards the viewer, per unit of the sun's (MODEL.md section 6,
// multiple scattering): world/formulas/volume.h. Exact values never go below its clamp
// (diffuseSunlight >= 1 / (1 + k tau_sun) >= exp(-tau_sun) for k <= 1), interpolated ones might.
using formulas::scatteredLight;

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
  double spacing = 0.0;            // metres between samples
  glm::dvec3 origin{0.0};          // grid-frame position of sample (0, 0, 0)
  std::vector<float> density;      // x fastest
  std::vector<float> sunlight;     // transmittance towards the sun, exp(-tau)
  std::vector<float> sun_diffuse;  // all the sunlight there, scattered or not (diffuseSunlight)
  std::vector<float> skylight;     // share of the sky light reaching the sample (sweepSkylight)
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

// Fills `lattice.sunlight` and `lattice.sun_diffuse` from the optical depths towards the sun and
// away from it, each found by one sweep from that side: a sample's optical depth is that of the
// point one slice further along (bilinear on that slice) plus the exact integral over the
// segment between them, with the density linear along it. O(samples).
void sweepSunlight(DensityLattice& lattice, glm::dvec3 to_sun,
                   double extinction_per_m = kCloudExtinctionPerMetre);
// Fills `lattice.skylight`: how much of the sky light reaches each sample through the cloud
// straight above it, diffuseTransmittance of that column's optical depth (MODEL.md section 6,
// sky light). A vertical column needs no interpolation: exact at every sample.
void sweepSkylight(DensityLattice& lattice, double extinction_per_m = kCloudExtinctionPerMetre);

// Transmittance of a segment whose density runs linearly from rho_a to rho_b
// (world/formulas/volume.h), at the cloud's extinction unless given.
inline double segmentTransmittance(double rho_a, double rho_b, double length,
                                   double extinction_per_m = kCloudExtinctionPerMetre) {
  return formulas::segmentTransmittance(rho_a, rho_b, length, extinction_per_m);
}

enum class PhaseFunction { kRayleigh, kCornetteShanks };

// Both integrate to 4 pi over the sphere (mean 1). cos_theta is the cosine of the scattering
// angle between the sunlight's direction of travel and the scattered ray's.
using formulas::cornetteShanksPhase;       // Shen eq. 11
using formulas::rayleighPhase;             // 3/4 (1 + cos^2)
double cornetteShanksAsymmetry(double u);  // Shen eq. 12-13, g(u)

}  // namespace nephele
