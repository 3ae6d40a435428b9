// Gardner's cluster generator against what it must be: deterministic, inside its boundary,
// as dense as its spacing says, raised exactly by the terrain under it, and refusing what
// cannot be built.
#include "world/formations/cluster.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace nephele {
namespace {

using ::testing::HasSubstr;

ClusterSpec field() {
  ClusterSpec s;
  s.element.radii = {300.0, 250.0, 150.0};
  s.centre = {12000.0, -4000.0};
  s.boundary_radii = {3000.0, 2000.0};
  s.boundary_heading_deg = 30.0;
  s.spacing = {500.0, 500.0};
  s.seed = 7;
  return s;
}

bool same(const Ellipsoid& a, const Ellipsoid& b) {
  return a.radii == b.radii && a.centre == b.centre &&
         a.orientation.heading_deg == b.orientation.heading_deg;
}

TEST(Cluster, TheSameDescriptionGivesTheSameEllipsoids) {
  const auto a = clusterEllipsoids(field());
  const auto b = clusterEllipsoids(field());
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_TRUE(same(a[i], b[i])) << i;
  ClusterSpec other = field();
  other.seed = 8;
  const auto c = clusterEllipsoids(other);
  int differ = 0;
  for (std::size_t i = 0; i < std::min(a.size(), c.size()); ++i) differ += !same(a[i], c[i]);
  EXPECT_GT(differ, int(a.size()) / 2);
}

TEST(Cluster, ElementsLieInsideTheBoundaryAsDenseAsTheSpacing) {
  const ClusterSpec s = field();
  const auto e = clusterEllipsoids(s);
  const double h = s.boundary_heading_deg * std::numbers::pi / 180.0;
  for (const Ellipsoid& x : e) {
    const glm::dvec2 d = glm::dvec2(x.centre) - s.centre;
    // Back into the boundary's frame (its x axis is east turned clockwise by the heading).
    const glm::dvec2 local(d.x * std::cos(h) - d.y * std::sin(h),
                           d.x * std::sin(h) + d.y * std::cos(h));
    const glm::dvec2 q = local / s.boundary_radii;
    EXPECT_LE(glm::dot(q, q), 1.0 + 1e-12);
    EXPECT_EQ(x.centre.z, s.altitude_m);
    EXPECT_NEAR(x.radii.x / x.radii.z, 2.0, 1e-12);  // one scale per element keeps the shape
    EXPECT_LE(std::abs(x.radii.x / 300.0 - 1.0), s.size_variation + 1e-12);
  }
  const double expected = std::numbers::pi * 3000.0 * 2000.0 / (500.0 * 500.0);  // 75.4
  EXPECT_NEAR(double(e.size()), expected, 0.15 * expected);
}

TEST(Cluster, TerrainRaisesElementsByItsHeightThere) {
  // A dome 800 m high and 1000 m wide at the origin: its top above (x, 0) is
  // 800 sqrt(1 - (x / 1000)^2).
  Ellipsoid dome;
  dome.centre = {0.0, 0.0, 0.0};
  dome.radii = {1000.0, 1000.0, 800.0};
  const std::vector<Ellipsoid> terrain{dome};
  EXPECT_NEAR(terrainHeight(terrain, {0.0, 0.0}), 800.0, 1e-6);
  EXPECT_NEAR(terrainHeight(terrain, {600.0, 0.0}), 640.0, 1e-6);
  EXPECT_EQ(terrainHeight(terrain, {1500.0, 0.0}), 0.0);
  ClusterSpec s;
  s.element.radii = {200.0, 200.0, 200.0};
  s.boundary_radii = {2000.0, 2000.0};
  s.spacing = {400.0, 400.0};
  s.position_variation = 0.2;
  const auto raised = clusterEllipsoids(s, terrain);
  int on_dome = 0;
  for (const Ellipsoid& e : raised) {
    const double r = glm::length(glm::dvec2(e.centre)) / 1000.0;
    const double height = r < 1.0 ? 800.0 * std::sqrt(1.0 - r * r) : 0.0;
    EXPECT_NEAR(e.centre.z, s.altitude_m + height, 1e-6);
    on_dome += r < 1.0;
  }
  EXPECT_GT(on_dome, 10);
}

TEST(Cluster, ImpossibleDescriptionsAreRefusedAndBuildNothing) {
  struct Case {
    void (*change)(ClusterSpec&);
    const char* words;
  };
  const Case cases[] = {
      {[](ClusterSpec& s) { s.spacing.x = -500.0; }, "spacing x: -500 is out of range"},
      {[](ClusterSpec& s) { s.boundary_radii.y = 0.0; }, "boundary y: 0 is out of range"},
      {[](ClusterSpec& s) { s.size_variation = NAN; }, "size_variation"},
      {[](ClusterSpec& s) { s.element.radii.z = -1.0; }, "element: radius z"},
      {[](ClusterSpec& s) {
         s.spacing = {10.0, 10.0};
       },
       "lattice cells (allowed: at most 4096"},
      {[](ClusterSpec& s) { s.vertical_scale = 0.0; }, "vertical_scale"},
  };
  for (const Case& c : cases) {
    ClusterSpec s = field();
    c.change(s);
    EXPECT_THAT(clusterError(s), HasSubstr(c.words));
    EXPECT_TRUE(clusterEllipsoids(s).empty());
  }
  EXPECT_EQ(clusterError(field()), "");
}

}  // namespace
}  // namespace nephele
