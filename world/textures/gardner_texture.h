#pragma once
// Gardner's sum-of-sines texture (MODEL.md section 2), evaluated in double.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include <glm/glm.hpp>

#include "world/formulas/texture.h"

namespace nephele {

struct GardnerTextureParams {
  static constexpr int kMaxTerms = 8;
  // Components per term once rotated or jittered (MODEL.md section 2): four for the two
  // lowest terms, which carry most of the power, two for the others.
  static constexpr int kComponents = 4;
  static constexpr int kSplitTerms = 2;
  int terms = 5;              // n, 1..8
  double fx1 = 2.0e-3;        // base frequency along X, radians per metre
  double fy1 = 2.0e-3;        // base frequency along Y, radians per metre
  double t0 = 0.0;            // contrast offset, >= 0
  bool seeded_phases = true;  // add a seed-derived constant phase per term
  std::uint64_t seed = 0;
  // Lattice breaking (MODEL.md section 2); both 0 is Gardner's texture exactly. Otherwise each
  // planar term of SX and of SY is n components of amplitude C(i) / sqrt n (the same power;
  // n above), each in its own axes, turned by a seed-derived angle uniform in [-rotation_deg,
  // rotation_deg], scaled by a seed-derived factor 2^(j (2v - 1)), j = jitter_octaves, and
  // with its own phases: the octaves and their powers stay Gardner's, spread over the band
  // around each octave, no single lattice carries much of the power, and the sum never
  // repeats. The scale spread matters where the rotation must stay small (cirrus streaks keep
  // a direction). Solid textures ignore both.
  double rotation_deg = 0.0;
  double jitter_octaves = 0.0;
  // C(i+1) / C(i), the amplitude ratio between successive terms: Gardner's 0.707 halves the
  // power per octave; the genus table sets its own for the spectrum of real clouds (MODEL.md
  // section 2).
  double amplitude_ratio = 0.707;
};

// How terms above the local sampling frequency are removed (MODEL.md section 2).
enum class TermFilter {
  kFade,  // fade each term out over the octave below half the sampling frequency
  kCut,   // drop a term as soon as it exceeds half the sampling frequency
  kNone,  // keep every term (aliases; for measurement)
};

// Gardner's T from the two sums and k (MODEL.md section 2; world/formulas/texture.h).
using formulas::textureFromSums;

class GardnerTexture {
 public:
  explicit GardnerTexture(const GardnerTextureParams& params);

  const GardnerTextureParams& params() const { return params_; }
  int terms() const { return params_.terms; }
  double frequencyX(int i) const { return fx_[i]; }  // i is 0-based
  double frequencyY(int i) const { return fy_[i]; }
  double amplitude(int i) const { return c_[i]; }
  // Seed-derived constant phases, radians, of term i's component c (0 unless rotated).
  double phaseX(int i, int c = 0) const { return phx_[i][c]; }
  double phaseY(int i, int c = 0) const { return phy_[i][c]; }
  double normalisation() const { return k_; }  // k = 1 / (sum C + T0)^2
  // Components of term i: 1 for Gardner's lattice, else 4 for the two lowest terms and 2 for
  // the others; each has amplitude amplitude(i) / sqrt(components(i)).
  int components(int i) const {
    if (periodic()) return 1;
    return i < GardnerTextureParams::kSplitTerms ? GardnerTextureParams::kComponents : 2;
  }
  double componentAmplitude(int i) const { return c_[i] / std::sqrt(double(components(i))); }
  // X axis of component c of term i in SX and in SY (the Y axis is that turned 90 degrees
  // anticlockwise), of length the component's frequency factor (1 without jitter_octaves);
  // (1, 0) for Gardner's lattice.
  glm::dvec2 axisX(int i, int c) const { return ax_[i][c]; }
  glm::dvec2 axisY(int i, int c) const { return ay_[i][c]; }
  // False when the terms are rotated or jittered: the planar texture then never repeats.
  bool periodic() const { return params_.rotation_deg == 0.0 && params_.jitter_octaves == 0.0; }

  // Repeat lengths in metres: 4 pi / FX1 and 4 pi / FY1 (the phase terms run at half the
  // base frequency). For a rotated texture, the scale the term filter measures footprints in.
  glm::dvec2 period() const;

  // T at a planar point, drift already removed, with `term_count` terms in [0, n]; a
  // fractional count blends the truncations floor(count) and floor(count) + 1.
  double planar(glm::dvec2 p, double term_count) const;
  double planar(glm::dvec2 p) const { return planar(p, terms()); }
  // SX and SY at a planar point with every term, T0 included: T = k max(SX, 0) max(SY, 0).
  glm::dvec2 planarSums(glm::dvec2 p) const;
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
  double phx_[GardnerTextureParams::kMaxTerms][GardnerTextureParams::kComponents]{};
  double phy_[GardnerTextureParams::kMaxTerms][GardnerTextureParams::kComponents]{};
  glm::dvec2 ax_[GardnerTextureParams::kMaxTerms][GardnerTextureParams::kComponents];
  glm::dvec2 ay_[GardnerTextureParams::kMaxTerms][GardnerTextureParams::kComponents];
  double k_ = 1.0;
};

// Wraps x into [0, period).
double wrapPeriodic(double x, double period);
// The period of the texture's sines in their phase, which wrapPeriodic reduces phases by.
inline constexpr double kTwoPi = 2.0 * std::numbers::pi;

}  // namespace nephele
