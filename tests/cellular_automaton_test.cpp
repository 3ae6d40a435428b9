#include "world/automaton/cellular_automaton.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

namespace nephele {
namespace {

// An independent, cell-by-cell statement of MODEL.md section 6's growth rules on plain bool arrays.
struct PlainGrid {
  GridSize n;
  std::vector<bool> hum, act, cld;
  bool at(const std::vector<bool>& b, int i, int j, int k) const {
    if (i < 0 || j < 0 || k < 0 || i >= n.nx || j >= n.ny || k >= n.nz) return false;
    return b[(std::size_t(k) * n.ny + j) * n.nx + i];
  }
};

PlainGrid plainGrowth(const PlainGrid& g) {
  PlainGrid next = g;
  for (int k = 0; k < g.n.nz; ++k)
    for (int j = 0; j < g.n.ny; ++j)
      for (int i = 0; i < g.n.nx; ++i) {
        const std::size_t c = (std::size_t(k) * g.n.ny + j) * g.n.nx + i;
        const bool f =
            g.at(g.act, i + 1, j, k) || g.at(g.act, i - 1, j, k) || g.at(g.act, i, j + 1, k) ||
            g.at(g.act, i, j - 1, k) || g.at(g.act, i, j, k + 1) || g.at(g.act, i, j, k - 1) ||
            g.at(g.act, i + 2, j, k) || g.at(g.act, i - 2, j, k) || g.at(g.act, i, j + 2, k) ||
            g.at(g.act, i, j - 2, k) || g.at(g.act, i, j, k - 2);
        next.hum[c] = g.hum[c] && !g.act[c];
        next.cld[c] = g.cld[c] || g.act[c];
        next.act[c] = !g.act[c] && g.hum[c] && f;
      }
  return next;
}

CellularAutomaton fromPlain(const PlainGrid& g) {
  CellularAutomaton a(g.n, 1);
  for (int k = 0; k < g.n.nz; ++k)
    for (int j = 0; j < g.n.ny; ++j)
      for (int i = 0; i < g.n.nx; ++i) {
        const std::size_t c = (std::size_t(k) * g.n.ny + j) * g.n.nx + i;
        a.set(CellBit::kHum, i, j, k, g.hum[c]);
        a.set(CellBit::kAct, i, j, k, g.act[c]);
        a.set(CellBit::kCld, i, j, k, g.cld[c]);
      }
  return a;
}

void expectSame(const CellularAutomaton& a, const PlainGrid& g) {
  int mismatches = 0;
  for (int k = 0; k < g.n.nz; ++k)
    for (int j = 0; j < g.n.ny; ++j)
      for (int i = 0; i < g.n.nx; ++i) {
        const std::size_t c = (std::size_t(k) * g.n.ny + j) * g.n.nx + i;
        mismatches += a.get(CellBit::kHum, i, j, k) != g.hum[c];
        mismatches += a.get(CellBit::kAct, i, j, k) != g.act[c];
        mismatches += a.get(CellBit::kCld, i, j, k) != g.cld[c];
      }
  EXPECT_EQ(mismatches, 0);
}

AutomatonProbabilities uniformFields(GridSize n, double hum, double act, double ext) {
  AutomatonProbabilities p{ProbabilityField(n), ProbabilityField(n), ProbabilityField(n)};
  for (int k = 0; k < n.nz; ++k)
    for (int j = 0; j < n.ny; ++j)
      for (int i = 0; i < n.nx; ++i) {
        p.humidity.set(i, j, k, hum);
        p.activation.set(i, j, k, act);
        p.extinction.set(i, j, k, ext);
      }
  return p;
}

TEST(CellularAutomaton, OneActiveCellSpreadsToExactlyTheSpecNeighbourhood) {
  const GridSize n{9, 9, 9};
  CellularAutomaton a(n, 1);
  for (int k = 0; k < 9; ++k)
    for (int j = 0; j < 9; ++j)
      for (int i = 0; i < 9; ++i) a.set(CellBit::kHum, i, j, k, true);
  a.set(CellBit::kAct, 4, 4, 4, true);
  a.growth();
  // The active cell turns into cloud, loses its humidity and stops being active.
  EXPECT_TRUE(a.get(CellBit::kCld, 4, 4, 4));
  EXPECT_FALSE(a.get(CellBit::kAct, 4, 4, 4));
  EXPECT_FALSE(a.get(CellBit::kHum, 4, 4, 4));
  // A cell reads act at (i+-1, i+-2), (j+-1, j+-2), (k+-1) and k-2, so the active cell
  // reaches two cells up but only one down: 11 cells.
  const int expected[][3] = {{3, 4, 4}, {5, 4, 4}, {2, 4, 4}, {6, 4, 4}, {4, 3, 4}, {4, 5, 4},
                             {4, 2, 4}, {4, 6, 4}, {4, 4, 3}, {4, 4, 5}, {4, 4, 6}};
  for (const auto& c : expected) EXPECT_TRUE(a.get(CellBit::kAct, c[0], c[1], c[2]));
  EXPECT_FALSE(a.get(CellBit::kAct, 4, 4, 2));
  EXPECT_EQ(a.count(CellBit::kAct), 11);
  EXPECT_EQ(a.count(CellBit::kCld), 1);
}

TEST(CellularAutomaton, ActivationNeedsHumidity) {
  CellularAutomaton a({8, 8, 8}, 1);
  a.set(CellBit::kAct, 3, 3, 3, true);
  a.set(CellBit::kHum, 4, 3, 3, true);  // the only humid neighbour
  a.growth();
  EXPECT_EQ(a.count(CellBit::kAct), 1);
  EXPECT_TRUE(a.get(CellBit::kAct, 4, 3, 3));
}

TEST(CellularAutomaton, CellsOutsideTheGridReadZeroAcrossWordBoundaries) {
  // nx = 130 spans three words: spreading across bits 63/64 and 127/128 must carry.
  const GridSize n{130, 3, 3};
  CellularAutomaton a(n, 1);
  for (int i = 0; i < n.nx; ++i) a.set(CellBit::kHum, i, 1, 1, true);
  a.set(CellBit::kAct, 63, 1, 1, true);
  a.set(CellBit::kAct, 129, 1, 1, true);
  a.growth();
  for (int i : {61, 62, 64, 65, 127, 128}) EXPECT_TRUE(a.get(CellBit::kAct, i, 1, 1)) << i;
  EXPECT_EQ(a.count(CellBit::kAct), 6);
}

TEST(CellularAutomaton, GrowthMatchesACellByCellStatementOnRandomGrids) {
  std::mt19937 rng(7);
  for (const GridSize n : {GridSize{70, 9, 7}, GridSize{5, 6, 4}, GridSize{129, 3, 5}}) {
    PlainGrid g{n, {}, {}, {}};
    for (auto* b : {&g.hum, &g.act, &g.cld}) {
      b->resize(std::size_t(n.cells()));
      for (std::size_t c = 0; c < b->size(); ++c) (*b)[c] = (rng() % 4) == 0;
    }
    CellularAutomaton a = fromPlain(g);
    for (int s = 0; s < 3; ++s) {
      a.growth();
      g = plainGrowth(g);
      expectSame(a, g);
    }
  }
}

TEST(CellularAutomaton, ExtinctionAndSupplyFrequenciesMatchTheirProbabilities) {
  const GridSize n{128, 64, 8};  // 65536 cells
  const double cells = double(n.cells());
  auto fraction = [&](CellBit bit, const CellularAutomaton& a) { return a.count(bit) / cells; };
  // Every tolerance is 5 standard deviations of a binomial proportion.
  auto sigma5 = [&](double p) { return 5.0 * std::sqrt(p * (1.0 - p) / cells); };
  for (double p : {0.3, 0.05, 0.001}) {
    CellularAutomaton a(n, 42);
    for (int k = 0; k < n.nz; ++k)
      for (int j = 0; j < n.ny; ++j)
        for (int i = 0; i < n.nx; ++i) a.set(CellBit::kCld, i, j, k, true);
    a.stochastic(uniformFields(n, p, p, p));
    EXPECT_NEAR(fraction(CellBit::kCld, a), 1.0 - p, sigma5(p)) << "extinction " << p;
    EXPECT_NEAR(fraction(CellBit::kHum, a), p, sigma5(p)) << "humidity " << p;
    EXPECT_NEAR(fraction(CellBit::kAct, a), p, sigma5(p)) << "activation " << p;
  }
  // Per-cell probabilities: the lower half of the grid 0.2, the upper half 0.7, counted apart.
  AutomatonProbabilities p = uniformFields(n, 0.0, 0.0, 0.0);
  for (int k = 0; k < n.nz; ++k)
    for (int j = 0; j < n.ny; ++j)
      for (int i = 0; i < n.nx; ++i) p.humidity.set(i, j, k, k < n.nz / 2 ? 0.2 : 0.7);
  CellularAutomaton a(n, 5);
  a.stochastic(p);
  long low = 0, high = 0;
  for (int k = 0; k < n.nz; ++k)
    for (int j = 0; j < n.ny; ++j)
      for (int i = 0; i < n.nx; ++i) (k < n.nz / 2 ? low : high) += a.get(CellBit::kHum, i, j, k);
  const double half = cells / 2.0;
  EXPECT_NEAR(low / half, 0.2, 5.0 * std::sqrt(0.2 * 0.8 / half));
  EXPECT_NEAR(high / half, 0.7, 5.0 * std::sqrt(0.7 * 0.3 / half));
  EXPECT_EQ(a.count(CellBit::kAct), 0);  // p = 0 never fires
}

TEST(CellularAutomaton, ProbabilityOneAlwaysFiresAndDrawsDifferEachStep) {
  const GridSize n{64, 8, 4};
  CellularAutomaton a(n, 3);
  a.stochastic(uniformFields(n, 1.0, 0.0, 0.0));
  EXPECT_EQ(a.count(CellBit::kHum), n.cells());
  // Same cell, consecutive steps: the fraction hit in both is p^2, not p (fresh draws).
  CellularAutomaton b(n, 3);
  const AutomatonProbabilities half = uniformFields({n.nx, n.ny, n.nz}, 0.0, 0.0, 0.5);
  for (int k = 0; k < n.nz; ++k)
    for (int j = 0; j < n.ny; ++j)
      for (int i = 0; i < n.nx; ++i) b.set(CellBit::kCld, i, j, k, true);
  b.step(half);
  b.step(half);
  // cld survives two extinction draws with probability 1/4 (growth keeps cld).
  const double cells = double(n.cells());
  EXPECT_NEAR(b.count(CellBit::kCld) / cells, 0.25, 5.0 * std::sqrt(0.25 * 0.75 / cells));
}

TEST(CellularAutomaton, RunsAreBitIdenticalWhateverTheThreadCount) {
  const GridSize n{100, 40, 12};
  const AutomatonProbabilities p = uniformFields(n, 0.1, 0.01, 0.1);
  CellularAutomaton one(n, 99), three(n, 99), other_seed(n, 100);
  for (int s = 0; s < 25; ++s) {
    one.step(p, 1);
    three.step(p, 3);
    other_seed.step(p, 1);
  }
  EXPECT_GT(one.count(CellBit::kCld), 0);
  for (int b = 0; b < 3; ++b) EXPECT_EQ(one.words(CellBit(b)), three.words(CellBit(b)));
  EXPECT_NE(one.words(CellBit::kCld), other_seed.words(CellBit::kCld));
}

TEST(CellularAutomaton, WindShiftMovesWholeLayersAndDropsWhatLeaves) {
  const GridSize n{150, 6, 2};
  std::mt19937 rng(3);
  CellularAutomaton a(n, 1);
  for (int j = 0; j < n.ny; ++j)
    for (int i = 0; i < n.nx; ++i) a.set(CellBit::kCld, i, j, 1, rng() % 2);
  const CellularAutomaton before = a;
  for (const auto& [dx, dy] : {std::pair{1, 0}, {-70, 2}, {64, -1}, {-1, 0}, {200, 0}}) {
    a = before;
    a.shiftLayer(1, dx, dy);
    int wrong = 0;
    for (int j = 0; j < n.ny; ++j)
      for (int i = 0; i < n.nx; ++i)
        wrong += a.get(CellBit::kCld, i, j, 1) != before.get(CellBit::kCld, i - dx, j - dy, 1);
    EXPECT_EQ(wrong, 0) << dx << "," << dy;
  }
}

TEST(ProbabilityField, StoresProbabilitiesToSixteenBits) {
  ProbabilityField f({3, 2, 1});
  for (double p : {0.0, 1.0, 0.5, 0.001, 0.123456, 0.99999}) {
    f.set(2, 1, 0, p);
    EXPECT_NEAR(f.at(2, 1, 0), p, 0.5 / 65536.0) << p;
  }
  f.set(0, 0, 0, std::nan(""));
  EXPECT_EQ(f.at(0, 0, 0), 0.0);
}

}  // namespace
}  // namespace nephele
