#pragma once
// Values that change over simulation time: keyframes joined linearly, held beyond the ends.
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace nephele {

struct Schedule {
  std::vector<double> times_s;  // strictly increasing
  std::vector<double> values;   // one per time

  bool empty() const { return times_s.empty(); }
  // The value at time t, or `unscheduled` when there are no keyframes.
  double at(double t, double unscheduled) const;
};

// Empty when `schedule` is usable with values in [lo, hi], else what is wrong.
std::string scheduleError(const Schedule& schedule, double lo, double hi);

// Wind by altitude: velocities joined linearly between sample altitudes, held beyond them.
struct WindSample {
  double altitude_m = 0.0;
  glm::dvec2 velocity{0.0};  // metres per second towards +X (east) and +Y (north)
};

struct WindProfile {
  std::vector<WindSample> samples;  // strictly increasing altitude

  bool empty() const { return samples.empty(); }
  glm::dvec2 at(double altitude_m) const;  // zero without samples
};

}  // namespace nephele
