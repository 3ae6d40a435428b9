#include "world/solar.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "world/limits.h"

namespace nephele {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

double wrap360(double a) {
  a = std::fmod(a, 360.0);
  return a < 0.0 ? a + 360.0 : a;
}

bool leapYear(int y) {
  return (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
}

int daysInMonth(int y, int m) {
  static constexpr int kDays[] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  return m == 2 && leapYear(y) ? 29 : kDays[m - 1];
}

// Reads exactly `n` digits at `pos`.
bool digits(std::string_view text, std::size_t& pos, int n, int& out) {
  if (pos + std::size_t(n) > text.size()) return false;
  out = 0;
  for (int i = 0; i < n; ++i) {
    const char c = text[pos++];
    if (c < '0' || c > '9') return false;
    out = out * 10 + (c - '0');
  }
  return true;
}

bool expect(std::string_view text, std::size_t& pos, char c) {
  if (pos >= text.size() || text[pos] != c) return false;
  ++pos;
  return true;
}

}  // namespace

std::string civilTimeError(const CivilTime& t) {
  if (t.year < Limits::kMinSolarYear || t.year > Limits::kMaxSolarYear)
    return "year " + std::to_string(t.year) +
           " is out of range (allowed: " + std::to_string(Limits::kMinSolarYear) + " to " +
           std::to_string(Limits::kMaxSolarYear) + ")";
  if (t.month < 1 || t.month > 12) return "month " + std::to_string(t.month) + " is not 1 to 12";
  if (t.day < 1 || t.day > daysInMonth(t.year, t.month))
    return "day " + std::to_string(t.day) + " is not a day of that month";
  if (t.hour < 0 || t.hour > 23) return "hour " + std::to_string(t.hour) + " is not 0 to 23";
  if (t.minute < 0 || t.minute > 59)
    return "minute " + std::to_string(t.minute) + " is not 0 to 59";
  if (!(t.second >= 0.0 && t.second < 60.0)) return "second is not 0 to less than 60";
  return "";
}

std::string parseUtc(std::string_view text, CivilTime& out) {
  const std::string form =
      " (allowed: YYYY-MM-DDTHH:MM[:SS[.fff]] then Z or +HH:MM or -HH:MM, years " +
      std::to_string(Limits::kMinSolarYear) + " to " + std::to_string(Limits::kMaxSolarYear) + ")";
  CivilTime t;
  t.second = 0.0;
  std::size_t p = 0;
  const bool ok = digits(text, p, 4, t.year) && expect(text, p, '-') &&
                  digits(text, p, 2, t.month) && expect(text, p, '-') &&
                  digits(text, p, 2, t.day) && expect(text, p, 'T') && digits(text, p, 2, t.hour) &&
                  expect(text, p, ':') && digits(text, p, 2, t.minute);
  if (!ok) {
    // Appended in steps: GCC 12 warns falsely (-Wrestrict) on "\"" + std::string(...).
    std::string message(1, '"');
    message.append(text.substr(0, 40)).append("\" is not a date and time").append(form);
    return message;
  }
  if (p < text.size() && text[p] == ':') {
    ++p;
    int whole = 0;
    if (!digits(text, p, 2, whole)) return "the seconds are not two digits" + form;
    t.second = whole;
    if (p < text.size() && text[p] == '.') {
      ++p;
      double scale = 0.1;
      const std::size_t first = p;
      while (p < text.size() && text[p] >= '0' && text[p] <= '9' && p - first < 9) {
        t.second += scale * (text[p++] - '0');
        scale *= 0.1;
      }
      if (p == first) return "a '.' in the seconds needs digits after it" + form;
    }
  }
  int offset_minutes = 0;
  if (p < text.size() && text[p] == 'Z') {
    ++p;
  } else if (p < text.size() && (text[p] == '+' || text[p] == '-')) {
    const int sign = text[p++] == '+' ? 1 : -1;
    int oh = 0, om = 0;
    if (!digits(text, p, 2, oh) || !expect(text, p, ':') || !digits(text, p, 2, om) || oh > 14 ||
        om > 59)
      return "the offset from UTC is not +HH:MM or -HH:MM (at most 14 hours)" + form;
    offset_minutes = sign * (oh * 60 + om);
  } else {
    return "the time zone is missing" + form;
  }
  if (p != text.size()) return "text follows the time zone" + form;
  if (std::string e = civilTimeError(t); !e.empty()) return e + form;
  // Local time minus the offset is UTC; move by whole minutes across day, month and year.
  int minutes = t.hour * 60 + t.minute - offset_minutes;
  int day_shift = 0;
  while (minutes < 0) minutes += 1440, --day_shift;
  while (minutes >= 1440) minutes -= 1440, ++day_shift;
  t.hour = minutes / 60;
  t.minute = minutes % 60;
  t.day += day_shift;
  if (t.day < 1) {
    if (--t.month < 1) t.month = 12, --t.year;
    t.day = daysInMonth(t.year, t.month);
  } else if (t.day > daysInMonth(t.year, t.month)) {
    t.day = 1;
    if (++t.month > 12) t.month = 1, ++t.year;
  }
  if (std::string e = civilTimeError(t); !e.empty()) return e + " once turned to UTC" + form;
  out = t;
  return "";
}

std::string formatUtc(const CivilTime& t) {
  char text[40];
  std::snprintf(text, sizeof text, "%04d-%02d-%02dT%02d:%02d:%06.3fZ", t.year, t.month, t.day,
                t.hour, t.minute, t.second);
  return text;
}

double julianDay(const CivilTime& utc) {
  int y = utc.year, m = utc.month;
  if (m <= 2) --y, m += 12;
  const int a = y / 100;
  const int b = 2 - a + a / 4;
  const double day = utc.day + (utc.hour + (utc.minute + utc.second / 60.0) / 60.0) / 24.0;
  return std::floor(365.25 * (y + 4716)) + std::floor(30.6001 * (m + 1)) + day + b - 1524.5;
}

double greenwichSiderealDeg(double jd) {
  const double t = (jd - 2451545.0) / 36525.0;
  return wrap360(280.46061837 + 360.98564736629 * (jd - 2451545.0) + 0.000387933 * t * t -
                 t * t * t / 38710000.0);
}

SolarPosition solarPosition(const CivilTime& utc, double latitude_deg, double longitude_deg) {
  // Meeus chapter 25, "low accuracy": UT is used for TT (they differ by about a minute, a
  // quarter of an arc-minute of the sun's motion).
  const double jd = julianDay(utc);
  const double t = (jd - 2451545.0) / 36525.0;  // Julian centuries from J2000.0
  const double l0 = wrap360(280.46646 + t * (36000.76983 + 0.0003032 * t));  // eq. 25.2
  const double m = wrap360(357.52911 + t * (35999.05029 - 0.0001537 * t));   // eq. 25.3
  const double c = std::sin(m * kDeg) * (1.914602 - t * (0.004817 + 0.000014 * t)) +
                   std::sin(2.0 * m * kDeg) * (0.019993 - 0.000101 * t) +
                   std::sin(3.0 * m * kDeg) * 0.000289;  // equation of the centre
  const double omega = 125.04 - 1934.136 * t;
  const double lambda = l0 + c - 0.00569 - 0.00478 * std::sin(omega * kDeg);  // apparent
  const double eps0 =
      23.0 + (26.0 + (21.448 - t * (46.8150 + t * (0.00059 - t * 0.001813))) / 60.0) / 60.0;
  const double eps = eps0 + 0.00256 * std::cos(omega * kDeg);  // eq. 25.8, corrected
  const double alpha =
      std::atan2(std::cos(eps * kDeg) * std::sin(lambda * kDeg), std::cos(lambda * kDeg));
  const double delta = std::asin(std::sin(eps * kDeg) * std::sin(lambda * kDeg));
  // Local hour angle (Meeus chapter 13, longitude east positive here).
  const double h = (greenwichSiderealDeg(jd) + longitude_deg) * kDeg - alpha;
  const double phi = latitude_deg * kDeg;
  const double sin_e =
      std::sin(phi) * std::sin(delta) + std::cos(phi) * std::cos(delta) * std::cos(h);
  const double elevation = std::asin(std::clamp(sin_e, -1.0, 1.0));
  // Azimuth from north through east (Meeus eq. 13.5 measures from south; add 180 degrees).
  const double az_south =
      std::atan2(std::sin(h), std::cos(h) * std::sin(phi) - std::tan(delta) * std::cos(phi));
  return {wrap360(az_south / kDeg + 180.0), elevation / kDeg, delta / kDeg, wrap360(alpha / kDeg),
          wrap360(lambda)};
}

}  // namespace nephele
