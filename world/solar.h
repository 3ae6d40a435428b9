#pragma once
// The sun's place in the sky from the date, the time of day and the site (MODEL.md section
// 13): the low-precision solar coordinates of Meeus, Astronomical Algorithms (2nd ed.,
// chapters 12 and 25), as NOAA's solar calculator uses them. About 0.01 degree from 1901 to
// 2099; no refraction (the elevation is geometric, of the sun's centre).
#include <string>
#include <string_view>

namespace nephele {

// A moment in Coordinated Universal Time.
struct CivilTime {
  int year = 2000, month = 1, day = 1;
  int hour = 12, minute = 0;
  double second = 0.0;
  bool operator==(const CivilTime&) const = default;
};

// "YYYY-MM-DDTHH:MM[:SS[.fff]]" followed by "Z" or an offset "+HH:MM" / "-HH:MM" (ISO 8601),
// turned to UTC. Returns the error (naming what is allowed), or empty.
std::string parseUtc(std::string_view text, CivilTime& out);
// Checks a date and time of day (year limits from world/limits.h); empty when valid.
std::string civilTimeError(const CivilTime& t);
std::string formatUtc(const CivilTime& t);  // "YYYY-MM-DDTHH:MM:SS.sssZ"

// Julian Day of a UTC moment (Meeus eq. 7.1, Gregorian calendar).
double julianDay(const CivilTime& utc);

struct SolarPosition {
  double azimuth_deg;    // clockwise from north, 0 to 360
  double elevation_deg;  // above the horizon, geometric
  double declination_deg;
  double right_ascension_deg;
  double apparent_longitude_deg;
};

// The sun seen from latitude (north positive) and longitude (east positive), in degrees.
SolarPosition solarPosition(const CivilTime& utc, double latitude_deg, double longitude_deg);

// Greenwich mean sidereal time in degrees, 0 to 360 (Meeus eq. 12.4).
double greenwichSiderealDeg(double julian_day);

}  // namespace nephele
