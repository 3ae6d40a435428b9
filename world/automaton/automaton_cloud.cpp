#include "world/automaton/automaton_cloud.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "world/check.h"
#include "world/limits.h"

namespace nephele {
namespace {

constexpr double kNsPerSecond = 1e9;

// Whole cells a layer has moved after `steps` steps at a relative wind `velocity`.
glm::ivec2 shearCells(glm::dvec2 velocity, std::uint64_t steps, double interval_s, double cell) {
  return glm::ivec2(glm::floor(velocity * (double(steps) * interval_s / cell)));
}

}  // namespace

std::string automatonCloudError(const AutomatonCloudSpec& s) {
  std::ostringstream out;
  auto probability = [&](const char* key, double p, const Schedule& schedule) {
    if (!(p >= 0.0 && p <= 1.0))
      out << key << ": " << p << " (allowed: 0 to 1)";
    else if (std::string e = scheduleError(schedule, 0.0, 1.0); !e.empty())
      out << key << " schedule: " << e;
  };
  // The ranges of world/limits.h, which the scene reader uses too.
  const int kMaxSide = Limits::kMaxCellsPerAxis;
  if (s.cells.nx < 1 || s.cells.ny < 1 || s.cells.nz < 1 || s.cells.nx > kMaxSide ||
      s.cells.ny > kMaxSide || s.cells.nz > kMaxSide)
    out << "cells: " << s.cells.nx << "x" << s.cells.ny << "x" << s.cells.nz << " (allowed: 1 to "
        << kMaxSide << " per axis)";
  else if (s.cells.cells() > Limits::kMaxCells)
    out << "cells: " << s.cells.cells() << " cells (allowed: at most " << Limits::kMaxCells << ")";
  else if (!Limits::kCellSize.contains(s.cell_size_m))
    out << "cell_size: " << s.cell_size_m << " (allowed: " << Limits::kCellSize.lo << " to "
        << Limits::kCellSize.hi << " m)";
  else if (!Limits::kStepInterval.contains(s.step_interval_s))
    out << "step_interval: " << s.step_interval_s << " (allowed: " << Limits::kStepInterval.lo
        << " to " << Limits::kStepInterval.hi << " s)";
  else if (s.warmup_steps < 0 || s.warmup_steps > Limits::kMaxWarmupSteps)
    out << "warmup_steps: " << s.warmup_steps << " (allowed: 0 to " << Limits::kMaxWarmupSteps
        << ")";
  else if (s.samples_per_cell < 1 || s.samples_per_cell > Limits::kMaxSamplesPerCell)
    out << "samples_per_cell: " << s.samples_per_cell << " (allowed: 1 to "
        << Limits::kMaxSamplesPerCell << ")";
  else if (!std::isfinite(s.position.x) || !std::isfinite(s.position.y) ||
           !std::isfinite(s.position.z))
    out << "position: not finite (allowed: finite metres)";
  else if (!(s.ambient >= 0.0 && s.ambient <= 1.0))
    out << "ambient: " << s.ambient << " (allowed: 0 to 1)";
  else if (!(s.phase_u >= 0.0 && s.phase_u <= 1.0))
    out << "phase_u: " << s.phase_u << " (allowed: 0 to 1)";
  if (out.tellp() == 0) probability("humidity", s.humidity, s.humidity_schedule);
  if (out.tellp() == 0) probability("activation", s.activation, s.activation_schedule);
  if (out.tellp() == 0) probability("extinction", s.extinction, s.extinction_schedule);
  for (const ShapeEllipsoid& e : s.shape)
    if (out.tellp() == 0 && !(glm::all(glm::greaterThan(e.radii, glm::dvec3(0.0))) &&
                              glm::all(glm::lessThanEqual(e.radii, glm::dvec3(10.0))) &&
                              glm::all(glm::lessThanEqual(glm::abs(e.centre), glm::dvec3(10.0)))))
      out << "shape: radii must lie in (0, 10] and centres in [-10, 10] (fractions of the grid)";
  return out.str();
}

glm::dvec3 AutomatonCloudView::lowerBound() const {
  return corner + glm::dvec3((0.5 - kMetaballRadiusCells) * cell_size_m);
}

glm::dvec3 AutomatonCloudView::upperBound() const {
  return corner +
         (glm::dvec3(cells.nx, cells.ny, cells.nz) - 0.5 + kMetaballRadiusCells) * cell_size_m;
}

double AutomatonCloudView::exactDensity(glm::dvec3 world) const {
  const glm::dvec3 local = world - corner;
  double rho = 0.0;
  if (blend < 1.0) rho += (1.0 - blend) * metaballDensity(from->means, cells, cell_size_m, local);
  if (blend > 0.0) rho += blend * metaballDensity(to->means, cells, cell_size_m, local);
  return rho;
}

double AutomatonCloudView::phaseValue(double cos_theta) const {
  return phase == PhaseFunction::kRayleigh ? rayleighPhase(cos_theta)
                                           : cornetteShanksPhase(cos_theta, phase_g);
}

namespace {

std::string formatCount(double x) {
  std::ostringstream out;
  out << std::setprecision(3) << x;
  return out.str();
}

}  // namespace

std::string automatonWorkError(const std::vector<AutomatonCloudSpec>& automata, double time_s) {
  double points = 0.0, cell_steps = 0.0;
  for (const AutomatonCloudSpec& a : automata) {
    const double cells = double(a.cells.cells());
    points += cells * std::pow(double(a.samples_per_cell), 3.0);
    const double steps = a.warmup_steps + std::floor(std::max(time_s, 0.0) / a.step_interval_s) + 1;
    if (steps > Limits::kMaxAutomatonSteps)
      return "automaton " + a.name + ": reaching time " + formatCount(time_s) + " s takes " +
             formatCount(steps) + " steps (allowed: at most " +
             formatCount(Limits::kMaxAutomatonSteps) + "; lengthen step_interval or start earlier)";
    cell_steps += cells * steps;
  }
  if (points > double(Limits::kMaxLatticePoints))
    return "automata: " + formatCount(points) +
           " density lattice points (cells x samples_per_cell^3, summed) (allowed: at most " +
           formatCount(double(Limits::kMaxLatticePoints)) +
           "; use fewer or larger cells or fewer samples per cell)";
  if (cell_steps > Limits::kMaxCellSteps)
    return "automata: reaching time " + formatCount(time_s) + " s takes " +
           formatCount(cell_steps) + " cell-steps (cells x steps, summed) (allowed: at most " +
           formatCount(Limits::kMaxCellSteps) + ")";
  return "";
}

std::string automatonAdvanceError(const std::vector<AutomatonCloudSpec>& automata, double dt_s) {
  double steps = 0.0, cell_steps = 0.0;
  for (const AutomatonCloudSpec& a : automata) {
    const double n = std::ceil(dt_s / a.step_interval_s);
    steps += n;
    cell_steps += n * double(a.cells.cells());
  }
  if (steps > Limits::kMaxStepsPerAdvance || cell_steps > Limits::kMaxCellStepsPerAdvance)
    return "dt: " + formatCount(dt_s) + " s would run " + formatCount(steps) +
           " automaton steps over " + formatCount(cell_steps) +
           " cells (allowed per request: at most " + formatCount(Limits::kMaxStepsPerAdvance) +
           " steps and " + formatCount(Limits::kMaxCellStepsPerAdvance) +
           " cell-steps; advance in smaller pieces)";
  return "";
}

AutomatonCloud::AutomatonCloud(const AutomatonCloudSpec& spec, const WindProfile& wind,
                               glm::dvec3 to_sun, bool warm_up)
    : spec_(spec),
      wind_(wind),
      to_sun_(to_sun),
      previous_(spec.cells, spec.seed),
      current_(spec.cells, spec.seed) {
  NEPHELE_CHECK(automatonCloudError(spec).empty(), automatonCloudError(spec));
  std::vector<ShapeEllipsoid> shape = spec.shape;
  if (shape.empty()) shape.push_back({});
  const GridSize n = spec.cells;
  shape_weight_.resize(std::size_t(n.cells()));
  for (int k = 0; k < n.nz; ++k)
    for (int j = 0; j < n.ny; ++j)
      for (int i = 0; i < n.nx; ++i) {
        const glm::dvec3 f = (glm::dvec3(i, j, k) + 0.5) / glm::dvec3(n.nx, n.ny, n.nz);
        double weight = 0.0;
        for (const ShapeEllipsoid& e : shape) {
          const glm::dvec3 u = (f - e.centre) / e.radii;
          weight = std::max(weight, 1.0 - glm::dot(u, u));
        }
        shape_weight_[(std::size_t(k) * n.ny + j) * n.nx + i] = float(weight);
      }
  fields_ = {ProbabilityField(n), ProbabilityField(n), ProbabilityField(n)};
  if (warm_up) {
    updateProbabilities(0.0);
    for (int s = 0; s < spec.warmup_steps; ++s) current_.step(fields_);
    advanceTo(0, 1);
  }
}

std::int64_t AutomatonCloud::stepIntervalNs() const {
  return std::max<std::int64_t>(1, std::llround(spec_.step_interval_s * kNsPerSecond));
}

glm::dvec2 AutomatonCloud::gridWind() const {
  return wind_.at(spec_.position.z + 0.5 * spec_.cells.nz * spec_.cell_size_m);
}

void AutomatonCloud::updateProbabilities(double time_s) {
  const glm::dvec3 p(spec_.humidity_schedule.at(time_s, spec_.humidity),
                     spec_.activation_schedule.at(time_s, spec_.activation),
                     spec_.extinction_schedule.at(time_s, spec_.extinction));
  if (p == probabilities_) return;  // leave out the rebuild when nothing changed
  probabilities_ = p;
  const GridSize n = spec_.cells;
  for (int k = 0; k < n.nz; ++k)
    for (int j = 0; j < n.ny; ++j)
      for (int i = 0; i < n.nx; ++i) {
        const double w = std::max(0.0f, shape_weight_[(std::size_t(k) * n.ny + j) * n.nx + i]);
        fields_.humidity.set(i, j, k, p.x * w);
        fields_.activation.set(i, j, k, p.y * w);
        fields_.extinction.set(i, j, k, p.z + (1.0 - p.z) * std::pow(1.0 - w, 4));
      }
}

void AutomatonCloud::stepOnce(int threads) {
  const std::uint64_t s = stepsSinceStart() + 1;  // the state this step produces
  updateProbabilities(double(s) * spec_.step_interval_s);
  current_.step(fields_, threads);
  if (wind_.empty()) return;
  // Each layer shifts by its wind relative to the grid's.
  const GridSize n = spec_.cells;
  const double l = spec_.cell_size_m;
  const glm::dvec2 reference = gridWind();
  for (int k = 0; k < n.nz; ++k) {
    const glm::dvec2 relative = wind_.at(spec_.position.z + (k + 0.5) * l) - reference;
    const glm::ivec2 shift = shearCells(relative, s, spec_.step_interval_s, l) -
                             shearCells(relative, s - 1, spec_.step_interval_s, l);
    current_.shiftLayer(k, shift.x, shift.y);
  }
}

std::shared_ptr<AutomatonKeyframe> AutomatonCloud::keyframe(const CellularAutomaton& state) const {
  auto frame = std::make_shared<AutomatonKeyframe>();
  frame->step = state.steps();
  frame->means = cellMeans(state);
  frame->lattice =
      densityLattice(frame->means, spec_.cells, spec_.cell_size_m, spec_.samples_per_cell);
  sweepSunlight(frame->lattice, to_sun_);
  return frame;
}

void AutomatonCloud::rebuildKeyframes() {
  from_ = (to_ && to_->step == previous_.steps()) ? to_ : keyframe(previous_);
  to_ = keyframe(current_);
}

int AutomatonCloud::advanceTo(std::int64_t time_ns, int threads) {
  const std::uint64_t target =
      std::uint64_t(std::max<std::int64_t>(time_ns, 0) / stepIntervalNs()) + 1;
  int ran = 0;
  while (stepsSinceStart() < target) {
    // Only the last two states are shown; earlier ones need no copy.
    if (stepsSinceStart() + 1 == target) previous_ = current_;
    stepOnce(threads);
    ++ran;
  }
  if (ran > 0 || !to_) rebuildKeyframes();
  return ran;
}

glm::dvec2 AutomatonCloud::setWind(const WindProfile& wind, std::int64_t time_ns) {
  const glm::dvec2 before = gridWind();
  wind_ = wind;
  // view() places the grid at position + gridWind() t: keep that point at t.
  const glm::dvec2 shift = (before - gridWind()) * (double(time_ns) / kNsPerSecond);
  moveBy(shift);
  return shift;
}

bool AutomatonCloud::setSun(glm::dvec3 to_sun) {
  if (to_sun == to_sun_) return false;
  to_sun_ = to_sun;
  for (auto* frame : {&from_, &to_}) {
    if (!*frame) continue;
    auto relit = std::make_shared<AutomatonKeyframe>(**frame);
    sweepSunlight(relit->lattice, to_sun_);
    *frame = relit;
  }
  return true;
}

bool AutomatonCloud::restore(std::uint64_t previous_steps, const CellularAutomaton& previous,
                             const CellularAutomaton& current) {
  if (previous.size() != spec_.cells || current.size() != spec_.cells) return false;
  if (current.steps() != previous_steps + 1 || previous.steps() != previous_steps) return false;
  if (current.steps() < std::uint64_t(spec_.warmup_steps) + 1) return false;
  previous_ = previous;
  current_ = current;
  probabilities_ = glm::dvec3(-1.0);
  updateProbabilities(double(stepsSinceStart()) * spec_.step_interval_s);
  to_.reset();
  rebuildKeyframes();
  return true;
}

AutomatonCloudView AutomatonCloud::view(std::int64_t time_ns) const {
  AutomatonCloudView v;
  v.name = spec_.name;
  v.cells = spec_.cells;
  v.cell_size_m = spec_.cell_size_m;
  const double l = spec_.cell_size_m;
  const double t = double(time_ns) / kNsPerSecond;
  const glm::dvec2 drift = gridWind() * t;
  v.corner = spec_.position - glm::dvec3(0.5 * spec_.cells.nx * l, 0.5 * spec_.cells.ny * l, 0.0) +
             glm::dvec3(drift, 0.0);
  v.from = from_;
  v.to = to_;
  const std::int64_t from_time = std::int64_t(stepsSinceStart() - 1) * stepIntervalNs();
  v.blend = std::clamp(double(time_ns - from_time) / double(stepIntervalNs()), 0.0, 1.0);
  v.colour = spec_.colour;
  v.ambient = spec_.ambient;
  v.phase = spec_.phase;
  v.phase_g = cornetteShanksAsymmetry(spec_.phase_u);
  return v;
}

}  // namespace nephele
