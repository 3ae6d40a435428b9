#include "world/textures/gardner_texture.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "world/counter_random.h"
#include "world/formulas/texture.h"

namespace nephele {
double wrapPeriodic(double x, double period) {
  double r = std::fmod(x, period);
  if (r < 0.0) r += period;
  return r >= period ? 0.0 : r;  // -tiny + period may round up to period
}

GardnerTexture::GardnerTexture(const GardnerTextureParams& params) : params_(params) {
  double amplitude_sum = 0.0;
  double c = 1.0;
  for (int i = 0; i < params_.terms; ++i) {
    fx_[i] = params_.fx1 * std::ldexp(1.0, i);  // FX(i+1) = 2 FX(i)
    fy_[i] = params_.fy1 * std::ldexp(1.0, i);
    c_[i] = c;
    // n components of C / sqrt n keep the term's power; their sum can reach sqrt n C, which
    // k allows for so that T stays within [0, 1].
    amplitude_sum += c * std::sqrt(double(components(i)));
    c *= params_.amplitude_ratio;
    for (int k = 0; k < GardnerTextureParams::kComponents; ++k) {
      if (params_.seeded_phases && (k == 0 || !periodic())) {
        phx_[i][k] = kTwoPi * unitFromBits(hashCounters(params_.seed, 0x47617264ull, i, 2 * k));
        phy_[i][k] = kTwoPi * unitFromBits(hashCounters(params_.seed, 0x47617264ull, i, 2 * k + 1));
      }
      ax_[i][k] = ay_[i][k] = {1.0, 0.0};
    }
    if (!periodic()) {
      // Each component of SX and of SY turns by its own angle r (2u - 1), r = rotation_deg,
      // and scales by its own factor 2^(j (2v - 1)), j = jitter_octaves: the axis vector
      // carries both, so that every evaluator (here and the GL sky shader) applies them alike.
      const double r = params_.rotation_deg * std::numbers::pi / 180.0;
      const double j = params_.jitter_octaves;
      auto axis = [&](std::uint64_t which) {
        const double u = unitFromBits(hashCounters(params_.seed, 0x526f7461ull, i, which));
        const double v = unitFromBits(hashCounters(params_.seed, 0x4a697474ull, i, which));
        const double angle = r * (2.0 * u - 1.0);
        return std::exp2(j * (2.0 * v - 1.0)) * glm::dvec2(std::cos(angle), std::sin(angle));
      };
      for (int k = 0; k < components(i); ++k) {
        ax_[i][k] = axis(2 * k);
        ay_[i][k] = axis(2 * k + 1);
      }
    }
  }
  const double denom = amplitude_sum + params_.t0;
  k_ = 1.0 / (denom * denom);
}

glm::dvec2 GardnerTexture::period() const {
  return {4.0 * std::numbers::pi / params_.fx1, 4.0 * std::numbers::pi / params_.fy1};
}

double GardnerTexture::planar(glm::dvec2 p, double term_count) const {
  return evaluate({p.x, p.y, 0.0}, /*solid=*/false, term_count);
}

glm::dvec2 GardnerTexture::planarSums(glm::dvec2 p) const {
  double sx = params_.t0, sy = params_.t0;
  for (int i = 0; i < params_.terms; ++i) addTerm(i, {p.x, p.y, 0.0}, false, sx, sy);
  return {sx, sy};
}

double GardnerTexture::solid(glm::dvec3 p, double term_count) const {
  return evaluate(p, /*solid=*/true, term_count);
}

void GardnerTexture::addTerm(int i, glm::dvec3 p, bool solid, double& sx, double& sy) const {
  // Planar phases, plus the Z term for solid textures (MODEL.md section 2).
  if (solid || periodic()) {
    double px = 0.5 * std::numbers::pi * std::sin(0.5 * fy_[i] * p.y);
    double py = 0.5 * std::numbers::pi * std::sin(0.5 * fx_[i] * p.x);
    if (solid) {
      const double pz = std::numbers::pi * std::sin(0.5 * fx_[i] * p.z);
      px += pz;
      py += pz;
    }
    sx += c_[i] * std::sin(fx_[i] * p.x + px + phx_[i][0]);
    sy += c_[i] * std::sin(fy_[i] * p.y + py + phy_[i][0]);
    return;
  }
  // Lattice breaking: each component reads (x, y) in its own rotated axes.
  for (int k = 0; k < components(i); ++k) {
    const glm::dvec2 a = ax_[i][k], b = ay_[i][k];
    const double x1 = a.x * p.x + a.y * p.y, y1 = a.x * p.y - a.y * p.x;
    const double x2 = b.x * p.x + b.y * p.y, y2 = b.x * p.y - b.y * p.x;
    const double c = componentAmplitude(i);
    sx += c *
          std::sin(fx_[i] * x1 + 0.5 * std::numbers::pi * std::sin(0.5 * fy_[i] * y1) + phx_[i][k]);
    sy += c *
          std::sin(fy_[i] * y2 + 0.5 * std::numbers::pi * std::sin(0.5 * fx_[i] * x2) + phy_[i][k]);
  }
}

double GardnerTexture::evaluate(glm::dvec3 p, bool solid, double term_count) const {
  const int n = params_.terms;
  term_count = std::clamp(term_count, 0.0, double(n));
  const int whole = int(std::floor(term_count));
  const double fraction = term_count - whole;

  double sx = params_.t0, sy = params_.t0;
  for (int i = 0; i < whole; ++i) addTerm(i, p, solid, sx, sy);
  const double t_whole = textureFromSums(sx, sy, k_);
  if (fraction == 0.0 || whole >= n) return t_whole;

  addTerm(whole, p, solid, sx, sy);
  return glm::mix(t_whole, textureFromSums(sx, sy, k_), fraction);  // as the GPU blends them
}

double GardnerTexture::termCountForFootprint(double footprint_periods, TermFilter filter) const {
  const int n = params_.terms;
  // A zero or negative footprint resolves every term, an infinite one none (the formula's own
  // floor and log); one not known (NaN) every term.
  if (std::isnan(footprint_periods)) return n;
  static_assert(int(TermFilter::kFade) == formulas::kTermFade &&
                int(TermFilter::kCut) == formulas::kTermCut &&
                int(TermFilter::kNone) == formulas::kTermAll);
  return formulas::resolvedTerms(footprint_periods, double(n), int(filter));
}

}  // namespace nephele
