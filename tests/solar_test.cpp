// The sun from a date and time (world/solar.h) against the worked examples of Meeus,
// Astronomical Algorithms (2nd ed.), and against geometry whose answer is known.
#include "world/solar.h"

#include <gtest/gtest.h>

#include <cmath>

namespace nephele {
namespace {

CivilTime utc(int y, int mo, int d, int h, int mi, double s = 0.0) {
  CivilTime t;
  t.year = y, t.month = mo, t.day = d, t.hour = h, t.minute = mi, t.second = s;
  return t;
}

TEST(SolarTest, JulianDayMatchesMeeusExample7a) {
  // 1957 October 4.81 (Sputnik): JD 2436116.31; J2000.0 is JD 2451545.0.
  EXPECT_NEAR(julianDay(utc(1957, 10, 4, 19, 26, 24.0)), 2436116.31, 1e-6);
  EXPECT_DOUBLE_EQ(julianDay(utc(2000, 1, 1, 12, 0)), 2451545.0);
  // Across a leap day: 1 March follows 29 February 2024 by one day.
  EXPECT_DOUBLE_EQ(julianDay(utc(2024, 3, 1, 0, 0)) - julianDay(utc(2024, 2, 29, 0, 0)), 1.0);
}

TEST(SolarTest, SiderealTimeMatchesMeeusExamples12aAnd12b) {
  // 1987 April 10, 0h UT: 13h10m46.3668s; at 19h21m00s UT: 128.7378734 degrees.
  EXPECT_NEAR(greenwichSiderealDeg(julianDay(utc(1987, 4, 10, 0, 0))),
              (13.0 + 10.0 / 60.0 + 46.3668 / 3600.0) * 15.0, 1e-5);
  EXPECT_NEAR(greenwichSiderealDeg(julianDay(utc(1987, 4, 10, 19, 21))), 128.7378734, 1e-5);
}

TEST(SolarTest, SunCoordinatesMatchMeeusExample25a) {
  // 1992 October 13.0 TD: apparent longitude 199.90895, right ascension 198.38083,
  // declination -7.78507 degrees (the low-accuracy method of chapter 25; TD taken as UT).
  const SolarPosition p = solarPosition(utc(1992, 10, 13, 0, 0), 0.0, 0.0);
  EXPECT_NEAR(p.apparent_longitude_deg, 199.90895, 2e-3);
  EXPECT_NEAR(p.right_ascension_deg, 198.38083, 2e-3);
  EXPECT_NEAR(p.declination_deg, -7.78507, 2e-3);
}

TEST(SolarTest, AltitudeAndAzimuthFollowTheHourAngle) {
  // Noon at the tropic on the June solstice: the sun is near the zenith.
  const SolarPosition zenith = solarPosition(utc(2026, 6, 21, 12, 2), 23.44, 0.0);
  EXPECT_GT(zenith.elevation_deg, 89.5);
  // At 45 N, noon: due south at 90 - 45 + declination; in the morning in the east, in the
  // afternoon in the west, and the same height either side of the meridian.
  const SolarPosition noon = solarPosition(utc(2026, 6, 21, 12, 2), 45.0, 0.0);
  EXPECT_NEAR(noon.azimuth_deg, 180.0, 0.5);
  EXPECT_NEAR(noon.elevation_deg, 45.0 + noon.declination_deg, 0.02);
  const SolarPosition morning = solarPosition(utc(2026, 6, 21, 8, 2), 45.0, 0.0);
  const SolarPosition afternoon = solarPosition(utc(2026, 6, 21, 16, 2), 45.0, 0.0);
  EXPECT_GT(morning.azimuth_deg, 60.0);
  EXPECT_LT(morning.azimuth_deg, 120.0);
  EXPECT_NEAR(morning.azimuth_deg + afternoon.azimuth_deg, 360.0, 0.6);
  EXPECT_NEAR(morning.elevation_deg, afternoon.elevation_deg, 0.3);
  // East longitude brings noon earlier: 90 E has its noon at 06:00 UTC.
  EXPECT_NEAR(solarPosition(utc(2026, 6, 21, 6, 2), 45.0, 90.0).azimuth_deg, 180.0, 0.5);
  // Midnight in the polar summer: the sun is up, due north.
  const SolarPosition polar = solarPosition(utc(2026, 6, 21, 0, 2), 80.0, 0.0);
  EXPECT_NEAR(polar.elevation_deg, polar.declination_deg - 10.0, 0.05);
  EXPECT_NEAR(std::fmod(polar.azimuth_deg + 180.0, 360.0), 180.0, 0.5);
  // Every latitude and hour gives finite angles in range, poles included.
  for (double lat : {-90.0, -45.0, 0.0, 45.0, 90.0})
    for (int h = 0; h < 24; h += 5) {
      const SolarPosition q = solarPosition(utc(2026, 12, 21, h, 0), lat, 179.9);
      EXPECT_TRUE(std::isfinite(q.azimuth_deg) && q.azimuth_deg >= 0.0 && q.azimuth_deg < 360.0);
      EXPECT_TRUE(q.elevation_deg >= -90.0 && q.elevation_deg <= 90.0);
    }
}

TEST(SolarTest, UtcTextIsReadOrRefusedWithWhatIsAllowed) {
  CivilTime t;
  ASSERT_EQ(parseUtc("2026-01-01T00:30+01:00", t), "");
  EXPECT_EQ(t, utc(2025, 12, 31, 23, 30));
  ASSERT_EQ(parseUtc("2024-02-28T23:15:30.25-01:00", t), "");
  EXPECT_EQ(t, utc(2024, 2, 29, 0, 15, 30.25));
  ASSERT_EQ(parseUtc("2026-06-21T12:00Z", t), "");
  EXPECT_EQ(formatUtc(t), "2026-06-21T12:00:00.000Z");
  const CivilTime kept = t;
  for (const char* bad : {"2026-02-29T00:00Z", "2026-06-21T12:00", "2026-06-21 12:00Z",
                          "2100-01-01T00:00Z", "2026-06-21T24:00Z", "2026-06-21T12:00Zx",
                          "2026-13-01T00:00Z", "2099-12-31T23:30-01:00", ""}) {
    const std::string e = parseUtc(bad, t);
    EXPECT_NE(e, "") << bad;
    EXPECT_NE(e.find("allowed"), std::string::npos) << e;
  }
  EXPECT_EQ(t, kept);  // a refused text changes nothing
}

}  // namespace
}  // namespace nephele
