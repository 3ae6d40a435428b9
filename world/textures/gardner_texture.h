#pragma once
// Gardner's sum-of-sines texture (MODEL.md section 2), evaluated in double.
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace nephele {

struct GardnerTextureParams {
  static constexpr int kMaxTerms = 8;
  int terms = 5;              // n, 1..8
  double fx1 = 2.0e-3;        // base frequency along X, radians per metre
  double fy1 = 2.0e-3;        // base frequency along Y, radians per metre
  double t0 = 0.0;            // contrast offset, >= 0
  bool seeded_phases = true;  // add a seed-derived constant phase per term
  std::uint64_t seed = 0;
};

// How terms above the local sampling frequency are removed (MODEL.md section 2).
enum class TermFilter {
  kFade,  // fade each term out over the octave below half the sampling frequency
  kCut,   // drop a term as soon as it exceeds half the sampling frequency
  kNone,  // keep every term (aliases; for measurement)
};

class GardnerTexture {
 public:
  explicit GardnerTexture(const GardnerTextureParams& params);

  const GardnerTextureParams& params() const { return params_; }
  int terms() const { return params_.terms; }
  double frequencyX(int i) const { return fx_[i]; }  // i is 0-based
  double frequencyY(int i) const { return fy_[i]; }
  double amplitude(int i) const { return c_[i]; }
  double phaseX(int i) const { return phx_[i]; }  // seed-derived constant phase, radians
  double phaseY(int i) const { return phy_[i]; }
  double normalisation() const { return k_; }  // k = 1 / (sum C + T0)^2

  // Repeat lengths in metres: 4 pi / FX1 and 4 pi / FY1 (the phase terms run at half the
  // base frequency).
  glm::dvec2 period() const;

  // T at a planar point, drift already removed, with `term_count` terms in [0, n]; a
  // fractional count blends the truncations floor(count) and floor(count) + 1.
  double planar(glm::dvec2 p, double term_count) const;
  double planar(glm::dvec2 p) const { return planar(p, terms()); }
  // T with solid phases (ellipsoids).
  double solid(glm::dvec3 p, double term_count) const;

  // Term count for a pixel whose footprint is `footprint_periods` long, measured in units of
  // the texture period (term i, 1-based, has 2^i cycles per period).
  double termCountForFootprint(double footprint_periods, TermFilter filter) const;

 private:
  double evaluate(glm::dvec3 p, bool solid, double term_count) const;
  void addTerm(int i, glm::dvec3 p, bool solid, double& sx, double& sy) const;

  GardnerTextureParams params_;
  double fx_[GardnerTextureParams::kMaxTerms]{};
  double fy_[GardnerTextureParams::kMaxTerms]{};
  double c_[GardnerTextureParams::kMaxTerms]{};
  double phx_[GardnerTextureParams::kMaxTerms]{};
  double phy_[GardnerTextureParams::kMaxTerms]{};
  double k_ = 1.0;
};

// Wraps x into [0, period).
double wrapPeriodic(double x, double period);

}  // namespace nephele
