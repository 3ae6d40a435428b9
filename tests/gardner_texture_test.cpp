#include "world/textures/gardner_texture.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "world/textures/layer_texture.h"

namespace nephele {
namespace {

constexpr double kPi = std::numbers::pi;

// MODEL.md section 2 written out independently: m of n terms, k for all n terms.
double specTexture(const GardnerTexture& g, glm::dvec3 p, int m, bool solid) {
  const GardnerTextureParams& params = g.params();
  double c = 1.0, sum_c = 0.0, sx = params.t0, sy = params.t0;
  double fx = params.fx1, fy = params.fy1;
  for (int i = 0; i < params.terms; ++i) {
    sum_c += c;
    if (i < m) {
      double px = kPi / 2 * std::sin(0.5 * fy * p.y), py = kPi / 2 * std::sin(0.5 * fx * p.x);
      if (solid) {
        px += kPi * std::sin(0.5 * fx * p.z);
        py += kPi * std::sin(0.5 * fx * p.z);
      }
      sx += c * std::sin(fx * p.x + px + g.phaseX(i));
      sy += c * std::sin(fy * p.y + py + g.phaseY(i));
    }
    fx *= 2.0, fy *= 2.0, c *= 0.707;
  }
  const double k = 1.0 / ((sum_c + params.t0) * (sum_c + params.t0));
  return k * std::max(sx, 0.0) * std::max(sy, 0.0);
}

GardnerTextureParams params(int terms, double t0, std::uint64_t seed = 9) {
  GardnerTextureParams p;
  p.terms = terms;
  p.fx1 = 1.3e-3;
  p.fy1 = 0.7e-3;
  p.t0 = t0;
  p.seed = seed;
  return p;
}

TEST(GardnerTexture, StaysWithinZeroAndOne) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> coordinate(-1e6, 1e6);
  for (int n = 1; n <= 8; ++n)
    for (double t0 : {0.0, 0.5, 3.0}) {
      const GardnerTexture g(params(n, t0));
      double highest = 0.0;
      for (int i = 0; i < 2000; ++i) {
        const double t = g.planar({coordinate(rng), coordinate(rng)});
        ASSERT_GE(t, 0.0);
        ASSERT_LE(t, 1.0);
        highest = std::max(highest, t);
      }
      EXPECT_GT(highest, 0.0) << "n=" << n << " t0=" << t0;
    }
}

// Lattice breaking (MODEL.md section 2) written out: n = 4 components for terms 1 and 2, 2 for
// the others, each turned by at most `rotation_deg`, scaled by 2^(+-jitter), of amplitude
// C / sqrt n; k = 1 / (sum sqrt(n) C + T0)^2.
TEST(GardnerTexture, LatticeBreakingFollowsTheModel) {
  GardnerTextureParams p = params(5, 0.4);
  p.rotation_deg = 30.0;
  p.jitter_octaves = 0.5;
  const GardnerTexture g(p);
  ASSERT_FALSE(g.periodic());
  auto components = [](int i) { return i < 2 ? 4 : 2; };
  double sum_c = 0.0;
  for (int i = 0; i < p.terms; ++i) {
    ASSERT_EQ(g.components(i), components(i));
    sum_c += std::sqrt(components(i)) * g.amplitude(i);
  }
  const double k = 1.0 / ((sum_c + p.t0) * (sum_c + p.t0));
  EXPECT_DOUBLE_EQ(g.normalisation(), k);
  bool scaled_up = false, scaled_down = false;
  for (int i = 0; i < p.terms; ++i)
    for (int c = 0; c < components(i); ++c)
      for (const glm::dvec2 a : {g.axisX(i, c), g.axisY(i, c)}) {
        const double length = glm::length(a), angle = std::atan2(a.y, a.x) * 180.0 / kPi;
        EXPECT_GE(length, std::exp2(-0.5) - 1e-12);
        EXPECT_LE(length, std::exp2(0.5) + 1e-12);
        EXPECT_LE(std::abs(angle), 30.0 + 1e-9);
        scaled_up |= length > 1.1, scaled_down |= length < 0.9;
      }
  EXPECT_TRUE(scaled_up && scaled_down) << "the seeded scales spread both ways";
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> coordinate(-1e5, 1e5);
  double mismatch = 0.0;
  for (int n = 0; n < 500; ++n) {
    const glm::dvec2 q(coordinate(rng), coordinate(rng));
    double sx = p.t0, sy = p.t0;
    for (int i = 0; i < p.terms; ++i)
      for (int c = 0; c < components(i); ++c) {
        const glm::dvec2 a = g.axisX(i, c), b = g.axisY(i, c);
        const double x1 = a.x * q.x + a.y * q.y, y1 = a.x * q.y - a.y * q.x;
        const double x2 = b.x * q.x + b.y * q.y, y2 = b.x * q.y - b.y * q.x;
        const double fx = g.frequencyX(i), fy = g.frequencyY(i);
        const double ci = g.amplitude(i) / std::sqrt(components(i));
        sx += ci * std::sin(fx * x1 + kPi / 2 * std::sin(0.5 * fy * y1) + g.phaseX(i, c));
        sy += ci * std::sin(fy * y2 + kPi / 2 * std::sin(0.5 * fx * x2) + g.phaseY(i, c));
      }
    const double expected = k * std::max(sx, 0.0) * std::max(sy, 0.0);
    const double t = g.planar(q);
    ASSERT_GE(t, 0.0);
    ASSERT_LE(t, 1.0);
    mismatch = std::max(mismatch, std::abs(t - expected));
  }
  EXPECT_LT(mismatch, 1e-12);
  // Jitter alone breaks the lattice too: the texture no longer repeats with Gardner's period.
  GardnerTextureParams jittered = params(5, 0.4);
  jittered.jitter_octaves = 0.5;
  const GardnerTexture j(jittered);
  EXPECT_FALSE(j.periodic());
  double moved = 0.0;
  for (int n = 0; n < 50; ++n) {
    const glm::dvec2 q(coordinate(rng), coordinate(rng));
    moved = std::max(moved, std::abs(j.planar(q) - j.planar(q + j.period())));
  }
  EXPECT_GT(moved, 0.01);
}

TEST(GardnerTexture, FrequencyAndAmplitudeRelations) {
  const GardnerTexture g(params(8, 0.4));
  double sum = 0.0;
  for (int i = 0; i < 8; ++i) {
    sum += g.amplitude(i);
    if (i == 0) {
      EXPECT_EQ(g.amplitude(0), 1.0);
      EXPECT_EQ(g.frequencyX(0), 1.3e-3);
      continue;
    }
    EXPECT_DOUBLE_EQ(g.frequencyX(i), 2.0 * g.frequencyX(i - 1));
    EXPECT_DOUBLE_EQ(g.frequencyY(i), 2.0 * g.frequencyY(i - 1));
    EXPECT_DOUBLE_EQ(g.amplitude(i), 0.707 * g.amplitude(i - 1));
  }
  EXPECT_DOUBLE_EQ(g.normalisation(), 1.0 / ((sum + 0.4) * (sum + 0.4)));
}

// A genus's amplitude ratio replaces Gardner's 0.707 (MODEL.md section 2): C(i) = r^(i-1),
// and k still keeps T within [0, 1], reaching 1 where every sine is at its crest.
TEST(GardnerTexture, AmplitudeRatioSetsTheSpectrumAndKKeepsTWithinRange) {
  for (double r : {0.35, 0.86}) {
    GardnerTextureParams p = params(6, 0.5);
    p.amplitude_ratio = r;
    const GardnerTexture g(p);
    double sum = 0.0;
    for (int i = 0; i < 6; ++i) {
      EXPECT_DOUBLE_EQ(g.amplitude(i), std::pow(r, i));
      sum += g.amplitude(i);
    }
    EXPECT_DOUBLE_EQ(g.normalisation(), 1.0 / ((sum + 0.5) * (sum + 0.5)));
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> coordinate(-5e4, 5e4);
    for (int i = 0; i < 2000; ++i) {
      const double t = g.planar({coordinate(rng), coordinate(rng)}, g.terms());
      ASSERT_GE(t, 0.0);
      ASSERT_LE(t, 1.0);
    }
  }
}

TEST(GardnerTexture, MatchesSpecFormulaWithPhaseShifts) {
  const GardnerTexture g(params(6, 0.3));
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> coordinate(-5e4, 5e4);
  for (int i = 0; i < 500; ++i) {
    const glm::dvec3 p(coordinate(rng), coordinate(rng), coordinate(rng));
    ASSERT_NEAR(g.planar({p.x, p.y}), specTexture(g, {p.x, p.y, 0.0}, 6, false), 1e-12);
    ASSERT_NEAR(g.solid(p, 6), specTexture(g, p, 6, true), 1e-12);
  }
}

TEST(GardnerTexture, SeededPhasesAreDeterministicAndPerSeed) {
  const GardnerTexture a(params(5, 0.0, 7)), b(params(5, 0.0, 7)), c(params(5, 0.0, 8));
  GardnerTextureParams unseeded = params(5, 0.0, 7);
  unseeded.seeded_phases = false;
  const GardnerTexture none(unseeded);
  int differing = 0;
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(a.phaseX(i), b.phaseX(i));
    EXPECT_GE(a.phaseX(i), 0.0);
    EXPECT_LT(a.phaseX(i), 2 * kPi);
    EXPECT_EQ(none.phaseX(i), 0.0);
    EXPECT_EQ(none.phaseY(i), 0.0);
    differing += a.phaseX(i) != c.phaseX(i);
  }
  EXPECT_EQ(differing, 5);
  EXPECT_NE(a.planar({1234.0, 567.0}), none.planar({1234.0, 567.0}));
}

TEST(GardnerTexture, RepeatsWithItsPeriod) {
  const GardnerTexture g(params(7, 0.2));
  const glm::dvec2 period = g.period();
  EXPECT_DOUBLE_EQ(period.x, 4 * kPi / 1.3e-3);
  for (double x : {0.0, 1234.5, -9876.0})
    for (double y : {0.0, 345.25}) {
      EXPECT_NEAR(g.planar({x + period.x, y}), g.planar({x, y}), 1e-10);
      EXPECT_NEAR(g.planar({x, y - 3 * period.y}), g.planar({x, y}), 1e-10);
    }
}

TEST(GardnerTexture, TruncationKeepsExactlyTheLowTerms) {
  const GardnerTexture g(params(6, 0.5));
  const glm::dvec2 p(8123.0, -2231.0);
  for (int m = 0; m <= 6; ++m)
    EXPECT_NEAR(g.planar(p, m), specTexture(g, {p.x, p.y, 0.0}, m, false), 1e-12) << m;
  // A fractional count blends the neighbouring truncations.
  EXPECT_NEAR(g.planar(p, 2.25), 0.75 * g.planar(p, 2) + 0.25 * g.planar(p, 3), 1e-12);
  // With no terms only the offset is left: k T0^2.
  EXPECT_NEAR(g.planar(p, 0), g.normalisation() * 0.25, 1e-15);
}

TEST(GardnerTexture, TermCountFollowsSamplingFrequency) {
  const GardnerTexture g(params(6, 0.0));
  // Term i (1-based) has 2^i cycles per period and resolves while 2^i * footprint <= 1/2.
  for (int i = 1; i <= 6; ++i) {
    const double at_limit = 0.5 / std::ldexp(1.0, i);
    EXPECT_EQ(g.termCountForFootprint(at_limit, TermFilter::kCut), i);
    EXPECT_EQ(g.termCountForFootprint(at_limit * 1.01, TermFilter::kCut), i - 1);
    // Fading: the term at its limit has weight 0 and full weight an octave below.
    EXPECT_NEAR(g.termCountForFootprint(at_limit, TermFilter::kFade), i - 1, 1e-12);
    EXPECT_NEAR(g.termCountForFootprint(at_limit / std::sqrt(2.0), TermFilter::kFade), i - 0.5,
                1e-12);
  }
  EXPECT_EQ(g.termCountForFootprint(1e-9, TermFilter::kFade), 6);
  EXPECT_EQ(g.termCountForFootprint(10.0, TermFilter::kFade), 0);
  EXPECT_EQ(g.termCountForFootprint(std::numeric_limits<double>::infinity(), TermFilter::kCut), 0);
  EXPECT_EQ(g.termCountForFootprint(10.0, TermFilter::kNone), 6);
}

LayerTextureSpec driftingSpec(glm::dvec2 velocity) {
  LayerTextureSpec spec;
  spec.gardner = params(5, 0.2);
  spec.seed = 4;
  spec.drift_velocity = velocity;
  return spec;
}

TEST(LayerTextureDrift, WrappedOffsetEqualsUnwrappedMotion) {
  const LayerTexture moving(driftingSpec({13.7, -4.1}));
  const LayerTexture still(driftingSpec({0.0, 0.0}));
  for (double t : {0.0, 1.0, 3600.0, 4.0 * 3600.0}) {
    const glm::dvec2 offset = moving.driftOffset(t);
    EXPECT_GE(offset.x, 0.0);
    EXPECT_LT(offset.x, moving.period().x);
    EXPECT_GE(offset.y, 0.0);
    EXPECT_LT(offset.y, moving.period().y);
    const glm::dvec2 p(523.0, 1711.0);
    EXPECT_NEAR(moving.value(p, t), still.value(p - glm::dvec2(13.7, -4.1) * t, 0.0), 1e-9)
        << "t=" << t;
  }
}

TEST(LayerTextureDrift, HoursOfDriftKeepFullPrecision) {
  const LayerTexture moving(driftingSpec({25.0, 0.0}));
  const double period = moving.period().x;
  const double t = 10.0 * 3600.0 + 0.125;
  const long double exact = std::fmod(25.0L * (long double)t, (long double)period);
  EXPECT_NEAR(moving.driftOffset(t).x, double(exact), 1e-9);
}

}  // namespace
}  // namespace nephele
