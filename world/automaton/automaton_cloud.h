#pragma once
// A cloud grown by the cellular automaton (Dobashi; Shen et al.): its settings, the automaton
// with its shaped probabilities, wind shear by layer, and the two density and light keyframes
// that a render blends between.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "world/automaton/cellular_automaton.h"
#include "world/automaton/cloud_density.h"
#include "world/schedule.h"

namespace nephele {

// Dobashi shapes a cloud with ellipsoids. A cell's weight w = max over the ellipsoids of
// 1 - |u|^2 (u the cell centre in the ellipsoid's unit frame; 0 outside all of them) sets
// p_hum = humidity w, p_act = activation w and p_ext = extinction + (1 - extinction)(1 - w)^4:
// vapour and seeds at the core, certain extinction outside. Centre and radii are fractions of
// the grid's extent along each axis.
struct ShapeEllipsoid {
  glm::dvec3 centre{0.5, 0.5, 0.5};
  glm::dvec3 radii{0.5, 0.5, 0.5};
};

struct AutomatonCloudSpec {
  std::string name;
  GridSize cells{20, 20, 20};
  double cell_size_m = 40.0;
  glm::dvec3 position{0.0, 0.0, 1500.0};  // centre of the grid's bottom face at time 0
  std::uint64_t seed = 1;
  double step_interval_s = 2.0;  // simulation time between automaton steps
  int warmup_steps = 40;         // steps run before time 0, so the cloud exists at the start
  // Probabilities at a shape's centre (weight 1). The defaults keep about 70 % of the core
  // cloudy in the steady state.
  double humidity = 0.3;
  double activation = 0.005;
  double extinction = 0.05;
  Schedule humidity_schedule, activation_schedule, extinction_schedule;  // override over time
  std::vector<ShapeEllipsoid> shape;  // none: one ellipsoid filling the grid
  glm::dvec3 colour{1.0, 1.0, 1.0};   // linear RGB albedo
  double ambient = 0.3;               // isotropic sky light, a fraction of the sun's
  PhaseFunction phase = PhaseFunction::kRayleigh;
  double phase_u = 0.8;      // Cornette-Shanks u (Shen: 0.7 to 0.85)
  int samples_per_cell = 2;  // density lattice resolution
};

// Empty when usable, else what is wrong and what is allowed.
std::string automatonCloudError(const AutomatonCloudSpec& spec);

// Empty when building `automata` and running them to `time_s` stays within the work and
// memory bounds of world/limits.h, else which bound is passed and by how much.
std::string automatonWorkError(const std::vector<AutomatonCloudSpec>& automata, double time_s);
// The same for one advance of `dt_s` by the daemon.
std::string automatonAdvanceError(const std::vector<AutomatonCloudSpec>& automata, double dt_s);

// What a render needs of one automaton state.
struct AutomatonKeyframe {
  std::uint64_t step = 0;
  std::vector<float> means;  // q per cell
  DensityLattice lattice;    // density and sunlight
};

// An automaton cloud as one render sees it: the grid now, and two keyframes to blend.
struct AutomatonCloudView {
  std::string name;
  glm::dvec3 corner{0.0};  // world position of the grid's lower corner
  GridSize cells;
  double cell_size_m = 0.0;
  std::shared_ptr<const AutomatonKeyframe> from, to;
  double blend = 0.0;  // 0 shows `from`, 1 shows `to`
  glm::dvec3 colour{1.0};
  double ambient = 0.0;
  PhaseFunction phase = PhaseFunction::kRayleigh;
  double phase_g = 0.0;  // Cornette-Shanks asymmetry

  glm::dvec3 lowerBound() const;  // world box where the density can be non-zero
  glm::dvec3 upperBound() const;
  // Density at a world point, blended in time (MODEL.md section 6: exact metaballs, the
  // reference's).
  double exactDensity(glm::dvec3 world) const;
  double phaseValue(double cos_theta) const;
};

class AutomatonCloud {
 public:
  // Builds the probability fields and runs the warm-up steps unless `warm_up` is false.
  AutomatonCloud(const AutomatonCloudSpec& spec, const WindProfile& wind, glm::dvec3 to_sun,
                 bool warm_up = true);

  const AutomatonCloudSpec& spec() const { return spec_; }
  const CellularAutomaton& automaton() const { return current_; }
  const CellularAutomaton& previous() const { return previous_; }
  const AutomatonProbabilities& probabilities() const { return fields_; }
  std::uint64_t stepsSinceStart() const { return current_.steps() - spec_.warmup_steps; }

  // Steps until the automaton holds the state after time t (the keyframe after t) and returns
  // the number of steps run. Keyframes are rebuilt only when a step ran.
  int advanceTo(std::int64_t time_ns, int threads);
  // Moves the grid by `by` (a re-centred world, World::setSite).
  void moveBy(glm::dvec2 by) { spec_.position += glm::dvec3(by, 0.0); }
  // The wind changed at time_ns (World::setWind): the grid stays where its drift has brought it
  // and rides the new wind from there, its layers sheared by it. Returns how far its position
  // at time 0 moved, which the world's copy of the spec moves too.
  glm::dvec2 setWind(const WindProfile& wind, std::int64_t time_ns);
  // Recomputes the sunlight when the sun moved; returns whether it did.
  bool setSun(glm::dvec3 to_sun);
  // Replaces both states (snapshots); false if they do not fit the grid.
  bool restore(std::uint64_t previous_steps, const CellularAutomaton& previous,
               const CellularAutomaton& current);

  AutomatonCloudView view(std::int64_t time_ns) const;
  std::int64_t stepIntervalNs() const;

 private:
  // The wind the grid rides with: the wind at its middle height.
  glm::dvec2 gridWind() const;
  void updateProbabilities(double time_s);
  void stepOnce(int threads);
  std::shared_ptr<AutomatonKeyframe> keyframe(const CellularAutomaton& state) const;
  void rebuildKeyframes();

  AutomatonCloudSpec spec_;
  WindProfile wind_;
  glm::dvec3 to_sun_;
  std::vector<float> shape_weight_;  // per cell
  glm::dvec3 probabilities_{-1.0};   // the values the fields were built for
  AutomatonProbabilities fields_;
  CellularAutomaton previous_, current_;
  std::shared_ptr<const AutomatonKeyframe> from_, to_;
};

}  // namespace nephele
