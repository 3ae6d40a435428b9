// The database on the Earth (world/geodesy.h, MODEL.md section 13) against computations that
// take another route: the reduced latitude for Earth-centred points, the meridian ellipse for
// the site's north, and round trips to a millimetre at 10, 100 and 1,000 km.
#include "world/geodesy.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace nephele {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kB = kWgs84A * (1.0 - kWgs84F);

// A point on the ellipsoid through its reduced latitude beta, tan beta = (b / a) tan phi:
// (a cos beta cos lon, a cos beta sin lon, b sin beta).
glm::dvec3 onEllipsoid(double latitude_deg, double longitude_deg) {
  const double beta =
      std::atan2(kB * std::sin(latitude_deg * kDeg), kWgs84A * std::cos(latitude_deg * kDeg));
  return {kWgs84A * std::cos(beta) * std::cos(longitude_deg * kDeg),
          kWgs84A * std::cos(beta) * std::sin(longitude_deg * kDeg), kB * std::sin(beta)};
}

TEST(Geodesy, EarthCentredPointsMatchTheReducedLatitude) {
  EXPECT_NEAR(glm::length(earthCentred({0.0, 0.0, 0.0}) - glm::dvec3(kWgs84A, 0.0, 0.0)), 0.0,
              1e-9);
  EXPECT_NEAR(glm::length(earthCentred({90.0, 0.0, 0.0}) - glm::dvec3(0.0, 0.0, kB)), 0.0, 1e-6);
  EXPECT_NEAR(glm::length(earthCentred({0.0, 90.0, 100.0}) - glm::dvec3(0.0, kWgs84A + 100.0, 0.0)),
              0.0, 1e-6);
  for (double lat : {-89.0, -51.5, -12.0, 0.3, 33.3, 45.0, 64.1, 88.0})
    for (double lon : {-179.0, -1.25, 0.0, 77.0, 180.0})
      EXPECT_NEAR(glm::length(earthCentred({lat, lon, 0.0}) - onEllipsoid(lat, lon)), 0.0, 1e-6)
          << lat << ", " << lon;
}

TEST(Geodesy, GeodeticFromEarthCentredInvertsItToAMillimetre) {
  for (double lat : {-90.0, -60.0, -0.001, 0.0, 27.5, 51.5, 89.999, 90.0})
    for (double lon : {-179.9, -45.0, 0.0, 135.0})
      for (double h : {-400.0, 0.0, 2000.0, 40000.0}) {
        const Geodetic g = geodeticFromEarthCentred(earthCentred({lat, lon, h}));
        EXPECT_NEAR(g.latitude_deg, lat, 1e-10) << lat << ", " << lon << ", " << h;
        if (std::abs(lat) < 90.0) {
          EXPECT_NEAR(g.longitude_deg, lon, 1e-10);
        }
        EXPECT_NEAR(g.height_m, h, 1e-3);
      }
}

// Along the site's meridian the north coordinate is the chord's projection in the meridian
// plane: with (r, z) = (N cos phi, N (1 - e^2) sin phi), north = -sin phi0 dr + cos phi0 dz.
TEST(Geodesy, NorthAlongTheMeridianIsTheMeridianEllipsesChord) {
  const double lat0 = 51.5, lon0 = -1.25;
  const LocalFrame frame(lat0, lon0);
  auto meridian = [](double lat) {
    const double e2 = kWgs84F * (2.0 - kWgs84F), s = std::sin(lat * kDeg);
    const double n = kWgs84A / std::sqrt(1.0 - e2 * s * s);
    return glm::dvec2(n * std::cos(lat * kDeg), n * (1.0 - e2) * s);
  };
  for (double km : {10.0, 100.0, 1000.0}) {
    const double lat = lat0 + km / 111.2;  // about km north
    const glm::dvec2 d = meridian(lat) - meridian(lat0);
    const double north = -std::sin(lat0 * kDeg) * d.x + std::cos(lat0 * kDeg) * d.y;
    const glm::dvec3 local = frame.toLocal({lat, lon0, 1234.0});
    EXPECT_NEAR(local.x, 0.0, 1e-6) << km;
    EXPECT_NEAR(local.y, north, 1e-6) << km;
    EXPECT_EQ(local.z, 1234.0);  // altitude stays altitude
  }
}

TEST(Geodesy, TheDatabaseAndTheEarthAgreeToAMillimetreOutTo1000Km) {
  for (const auto& [lat0, lon0] :
       {std::pair{51.5, -1.25}, {0.0, 179.9}, {-33.9, 151.2}, {78.2, 15.6}})
    for (double km : {0.0, 10.0, 100.0, 1000.0})
      for (double bearing : {0.0, 45.0, 90.0, 200.0, 315.0}) {
        const LocalFrame frame(lat0, lon0);
        const glm::dvec3 local(km * 1000.0 * std::sin(bearing * kDeg),
                               km * 1000.0 * std::cos(bearing * kDeg), 3000.0);
        const Geodetic g = frame.toGeodetic(local);
        const glm::dvec3 back = frame.toLocal(g);
        EXPECT_NEAR(glm::length(back - local), 0.0, 1e-3)
            << lat0 << ", " << lon0 << ": " << km << " km at " << bearing;
      }
  // The site is the origin.
  const Geodetic site = LocalFrame(51.5, -1.25).toGeodetic({0.0, 0.0, 10.0});
  EXPECT_NEAR(site.latitude_deg, 51.5, 1e-12);
  EXPECT_NEAR(site.longitude_deg, -1.25, 1e-12);
  EXPECT_EQ(site.height_m, 10.0);
}

}  // namespace
}  // namespace nephele
