#include "world/automaton/cloud_density.h"

#include <cmath>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

namespace nephele {
namespace {

TEST(MetaballField, IsOneAtTheCentreAndZeroFromTheRadiusOn) {
  EXPECT_DOUBLE_EQ(metaballField(0.0, 80.0), 1.0);
  EXPECT_NEAR(metaballField(80.0, 80.0), 0.0, 1e-15);
  EXPECT_EQ(metaballField(80.1, 80.0), 0.0);
  EXPECT_EQ(metaballField(std::nan(""), 80.0), 0.0);
  // f(R/2) = -4/9/64 + 17/9/16 - 22/9/4 + 1 = 0.5 exactly.
  EXPECT_NEAR(metaballField(40.0, 80.0), 0.5, 1e-15);
  double previous = 2.0;
  for (double r = 0.0; r <= 80.0; r += 0.5) {
    EXPECT_LT(metaballField(r, 80.0), previous);
    previous = metaballField(r, 80.0);
  }
}

CellularAutomaton fullGrid(GridSize n) {
  CellularAutomaton a(n, 1);
  for (int k = 0; k < n.nz; ++k)
    for (int j = 0; j < n.ny; ++j)
      for (int i = 0; i < n.nx; ++i) a.set(CellBit::kCld, i, j, k, true);
  return a;
}

TEST(CellMeans, AverageCloudOverTheThirtyThreeCellsWithinTwoCells) {
  CellularAutomaton a({9, 9, 9}, 1);
  a.set(CellBit::kCld, 4, 4, 4, true);
  const std::vector<float> q = cellMeans(a);
  auto at = [&](int i, int j, int k) { return q[(k * 9 + j) * 9 + i]; };
  EXPECT_FLOAT_EQ(at(4, 4, 4), 1.0f / 33.0f);
  EXPECT_FLOAT_EQ(at(6, 4, 4), 1.0f / 33.0f);  // distance 2: inside R
  EXPECT_FLOAT_EQ(at(5, 5, 4), 1.0f / 33.0f);  // distance sqrt 2
  EXPECT_EQ(at(6, 5, 4), 0.0f);                // distance sqrt 5: outside
  const std::vector<float> full = cellMeans(fullGrid({9, 9, 9}));
  EXPECT_NEAR(full[(4 * 9 + 4) * 9 + 4], 1.0f, 1e-6);
  EXPECT_LT(full[0], 0.5f);  // a corner sees cells outside the grid as clear
}

TEST(DensityLattice, SamplesEqualTheDirectMetaballSum) {
  CellularAutomaton a({6, 5, 4}, 1);
  a.set(CellBit::kCld, 2, 2, 1, true);
  a.set(CellBit::kCld, 3, 2, 2, true);
  a.set(CellBit::kCld, 5, 4, 3, true);
  const std::vector<float> q = cellMeans(a);
  for (int r : {1, 2, 3}) {
    const DensityLattice lattice = densityLattice(q, a.size(), 30.0, r);
    double worst = 0.0;
    for (int z = 0; z < lattice.dims.z; ++z)
      for (int y = 0; y < lattice.dims.y; ++y)
        for (int x = 0; x < lattice.dims.x; ++x) {
          const double direct = metaballDensity(q, a.size(), 30.0, lattice.position(x, y, z));
          worst = std::max(worst, std::abs(direct - lattice.density[lattice.index(x, y, z)]));
        }
    EXPECT_LT(worst, 1e-5) << r;
    // Beyond the lattice the density is 0: its faces are R from the outermost cell centres.
    EXPECT_EQ(metaballDensity(q, a.size(), 30.0, lattice.origin - 0.01), 0.0);
  }
}

// A lattice of uniform density: the transmittance towards the sun is exp(-Ex rho L), L the
// path to the lattice face the ray leaves by.
DensityLattice uniformLattice(glm::ivec3 dims, double spacing, float rho) {
  DensityLattice l;
  l.dims = dims;
  l.spacing = spacing;
  l.density.assign(std::size_t(dims.x) * dims.y * dims.z, rho);
  l.sunlight.assign(l.density.size(), 1.0f);
  return l;
}

double pathToBoxFace(glm::dvec3 p, glm::dvec3 d, glm::dvec3 extent) {
  double t = 1e300;
  for (int a = 0; a < 3; ++a) {
    if (d[a] > 0) t = std::min(t, (extent[a] - p[a]) / d[a]);
    if (d[a] < 0) t = std::min(t, -p[a] / d[a]);
  }
  return t;
}

TEST(SweepSunlight, UniformSlabTransmitsExpMinusExRhoL) {
  // Sun directions that move a whole number of samples per slice, so the sweep interpolates
  // nothing and must reproduce the exact exponential; thin (Ex rho h = 0.016 per sample) and
  // optically thick (8 per sample) density. Oblique suns with fractional steps blur the light
  // (the sweep's error, measured against the reference in the render tests).
  for (const glm::dvec3 direction :
       {glm::dvec3(0, 0, 1), glm::dvec3(1, 0, 1), glm::dvec3(1, -1, 1), glm::dvec3(0, 1, -1)})
    for (const auto& [rho, spacing] : {std::pair{1.0f, 1.0}, std::pair{10.0f, 49.0}}) {
      const glm::dvec3 to_sun = glm::normalize(direction);
      DensityLattice l = uniformLattice({30, 30, 30}, spacing, rho);
      sweepSunlight(l, to_sun);
      int checked = 0;
      for (int z = 0; z < 30; ++z)
        for (int y = 0; y < 30; ++y)
          for (int x = 0; x < 30; ++x) {
            const glm::dvec3 p = l.position(x, y, z);
            const double path = pathToBoxFace(p, to_sun, l.extent());
            // Only rays that leave through the face the sweep starts from see uniform density
            // all the way.
            const glm::dvec3 exit = p + to_sun * path;
            const double face = to_sun.z > 0 ? l.extent().z : 0.0;
            if (std::abs(exit.z - face) > 1e-9) continue;
            // The sweep's first slice adds half a segment (the density at a lattice's edge
            // is where it has fallen to 0).
            const double length = path + 0.5 * spacing / std::abs(to_sun.z);
            const double expected = std::exp(-kCloudExtinctionPerMetre * rho * length);
            const double got = l.sunlight[l.index(x, y, z)];
            ASSERT_TRUE(std::isfinite(got));
            if (expected > 1e-30) {
              EXPECT_NEAR(got / expected, 1.0, 1e-4) << x << "," << y << "," << z;
            }
            ++checked;
          }
      EXPECT_GT(checked, 1000);
    }
}

TEST(SweepSunlight, StaysInRangeForAnySunAndExtremeDensity) {
  for (const glm::dvec3 sun : {glm::dvec3(0, 0, 1), glm::dvec3(1, 0, 0), glm::dvec3(0, -1, 0),
                               glm::dvec3(0.7, 0.7, 0.01), glm::dvec3(0, 0, -1)}) {
    DensityLattice l = uniformLattice({12, 9, 7}, 100.0, 1e6f);
    sweepSunlight(l, sun);
    for (float t : l.sunlight) ASSERT_TRUE(t >= 0.0f && t <= 1.0f);
    for (float d : l.sun_diffuse) ASSERT_TRUE(d > 0.0f && d < 2.0f);
    DensityLattice empty = uniformLattice({12, 9, 7}, 100.0, 0.0f);
    sweepSunlight(empty, sun);
    for (float t : empty.sunlight) ASSERT_EQ(t, 1.0f);
    for (float d : empty.sun_diffuse) ASSERT_EQ(d, 1.0f);
  }
}

TEST(SweepSkylight, EachSampleSeesTheExactColumnAboveIt) {
  // Density varying sample to sample (thin and thick): each sample's skylight is the two-stream
  // transmittance of the trapezoid sum of Ex rho up its column, plus half a segment falling to
  // 0 above the top sample; it falls with depth and never reaches 0.
  for (const float scale : {0.5f, 200.0f}) {
    DensityLattice l = uniformLattice({5, 4, 40}, 20.0, 0.0f);
    for (std::size_t i = 0; i < l.density.size(); ++i)
      l.density[i] = scale * float((i * 7919) % 101) / 100.0f;
    sweepSkylight(l);
    ASSERT_EQ(l.skylight.size(), l.density.size());
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 5; ++x) {
        double tau = kCloudExtinctionPerMetre * 0.5 * l.density[l.index(x, y, 39)] * 10.0;
        for (int z = 39; z >= 0; --z) {
          if (z < 39)
            tau += kCloudExtinctionPerMetre * 0.5 *
                   (l.density[l.index(x, y, z)] + l.density[l.index(x, y, z + 1)]) * 20.0;
          const double got = l.skylight[l.index(x, y, z)];
          ASSERT_GT(got, 0.0);
          ASSERT_LE(got, 1.0);
          EXPECT_NEAR(got, 1.0 / (1.0 + 0.75 * 0.15 * tau), 1e-6) << x << "," << y << "," << z;
          if (z < 39) {
            EXPECT_LE(got, l.skylight[l.index(x, y, z + 1)]);
          }
        }
      }
  }
}

TEST(DiffuseSunlight, IsTheTwoStreamSolutionOfANonAbsorbingSlab) {
  // The two-stream equations of a non-absorbing slab, tau from the sunlit face: the flux along
  // the sun's ray F+ and against it F- both change as dF/dtau = -k (F+ - F-), k = 3/4 (1 - g),
  // with F+(0) = 1 and F-(depth) = 0. Integrated by RK4, F-(0) found by shooting (the
  // equations are linear); F+ + F- must be diffuseSunlight(tau, depth - tau).
  const double k = 0.75 * (1.0 - kDiffuseAsymmetry);
  for (const double depth : {0.5, 5.0, 40.0, 400.0}) {
    const int n = 20000;
    const double h = depth / n;
    auto run = [&](double back, std::vector<double>* sums) {
      double up = 1.0, down = back;  // F+, F-
      for (int i = 0; i < n; ++i) {
        if (sums) sums->push_back(up + down);
        auto slope = [&](double u, double d) { return -k * (u - d); };
        const double k1 = slope(up, down);
        const double k2 = slope(up + 0.5 * h * k1, down + 0.5 * h * k1);
        const double k3 = slope(up + 0.5 * h * k2, down + 0.5 * h * k2);
        const double k4 = slope(up + h * k3, down + h * k3);
        const double step = h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        up += step;
        down += step;
      }
      if (sums) sums->push_back(up + down);
      return down;  // F-(depth)
    };
    const double at0 = run(0.0, nullptr), at1 = run(1.0, nullptr);
    const double back = -at0 / (at1 - at0);
    std::vector<double> sums;
    EXPECT_NEAR(run(back, &sums), 0.0, 1e-9);
    for (int i = 0; i <= n; i += n / 10)
      EXPECT_NEAR(diffuseSunlight(i * h, depth - i * h), sums[i], 1e-9) << depth << " at " << i;
    // The far face lets through the diffuse transmittance, as the sky light's columns do.
    EXPECT_NEAR(diffuseSunlight(depth, 0.0), diffuseTransmittance(depth), 1e-15);
  }
  // Never below the unscattered beam, and finite for extreme depths.
  for (const double a : {0.0, 1e-3, 1.0, 30.0, 1e6})
    for (const double b : {0.0, 1.0, 1e6}) {
      const double d = diffuseSunlight(a, b);
      EXPECT_GE(d, std::exp(-a)) << a << "," << b;
      EXPECT_LT(d, 2.0);
    }
}

// 2 pi times the integral over cos theta in [-1, 1] (Simpson).
template <class F>
double sphereIntegral(F phase) {
  const int n = 200000;
  const double h = 2.0 / n;
  double sum = phase(-1.0) + phase(1.0);
  for (int i = 1; i < n; ++i) sum += (i % 2 ? 4.0 : 2.0) * phase(-1.0 + i * h);
  return 2.0 * std::numbers::pi * sum * h / 3.0;
}

TEST(PhaseFunctions, IntegrateToFourPi) {
  const double four_pi = 4.0 * std::numbers::pi;
  EXPECT_NEAR(sphereIntegral(rayleighPhase), four_pi, 1e-9);
  for (double g : {0.0, 0.3, 0.7, 0.85})
    EXPECT_NEAR(sphereIntegral([g](double c) { return cornetteShanksPhase(c, g); }), four_pi, 1e-6)
        << g;
  EXPECT_DOUBLE_EQ(cornetteShanksPhase(0.4, 0.0), rayleighPhase(0.4));
}

TEST(PhaseFunctions, CornetteShanksAsymmetryRunsFromZeroToOne) {
  EXPECT_NEAR(cornetteShanksAsymmetry(0.0), 0.0, 1e-12);
  EXPECT_NEAR(cornetteShanksAsymmetry(1.0), 1.0, 1e-3);
  double previous = -1.0;
  for (double u = 0.0; u <= 1.0; u += 0.05) {
    EXPECT_GT(cornetteShanksAsymmetry(u), previous);
    previous = cornetteShanksAsymmetry(u);
  }
  // Shen's range u in [0.7, 0.85] gives strongly forward scattering.
  EXPECT_GT(cornetteShanksAsymmetry(0.7), 0.6);
}

}  // namespace
}  // namespace nephele
