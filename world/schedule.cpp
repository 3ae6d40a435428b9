#include "world/schedule.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace nephele {
double Schedule::at(double t, double unscheduled) const {
  if (empty()) return unscheduled;
  if (t <= times_s.front()) return values.front();
  if (t >= times_s.back()) return values.back();
  const std::size_t i =
      std::size_t(std::upper_bound(times_s.begin(), times_s.end(), t) - times_s.begin());
  const double f = (t - times_s[i - 1]) / (times_s[i] - times_s[i - 1]);
  return values[i - 1] + (values[i] - values[i - 1]) * f;
}

std::string scheduleError(const Schedule& s, double lo, double hi) {
  std::ostringstream out;
  if (s.times_s.size() != s.values.size())
    out << s.times_s.size() << " times but " << s.values.size() << " values (one value per time)";
  for (std::size_t i = 0; out.tellp() == 0 && i < s.times_s.size(); ++i) {
    if (!std::isfinite(s.times_s[i]) || s.times_s[i] < 0.0)
      out << "time " << s.times_s[i] << " (allowed: finite, >= 0)";
    else if (i > 0 && !(s.times_s[i] > s.times_s[i - 1]))
      out << "times must increase strictly (" << s.times_s[i - 1] << " then " << s.times_s[i]
          << ")";
    else if (!(s.values[i] >= lo && s.values[i] <= hi))
      out << "value " << s.values[i] << " (allowed: " << lo << " to " << hi << ")";
  }
  return out.str();
}

glm::dvec2 WindProfile::at(double altitude_m) const {
  if (samples.empty()) return glm::dvec2(0.0);
  if (altitude_m <= samples.front().altitude_m) return samples.front().velocity;
  if (altitude_m >= samples.back().altitude_m) return samples.back().velocity;
  const auto upper =
      std::upper_bound(samples.begin(), samples.end(), altitude_m,
                       [](double z, const WindSample& s) { return z < s.altitude_m; });
  const WindSample& a = *(upper - 1);
  const WindSample& b = *upper;
  const double f = (altitude_m - a.altitude_m) / (b.altitude_m - a.altitude_m);
  return a.velocity + (b.velocity - a.velocity) * f;
}

}  // namespace nephele
