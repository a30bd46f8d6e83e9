// Gains for a target phase margin and crossover from the measured plant.
// With the crossover given (--bandwidth) the gains put L(j w_c) exactly at
// |L| = 1, angle -180 + PM. Without it every crossover over the coherent
// band is tried and the design with the largest low-frequency gain is kept
// (the integral gain ki for PI, the outer loop's velocity constant for
// P+V+dP: the smallest tracking error) among those that also
// keep a gain margin of at least 6 dB and a sensitivity peak of at most 2
// (6 dB) on the measured plant: a maximum-stiffness design under robustness
// constraints, in the manner of Astrom and Hagglund's MIGO. For a
// filtered step the PI's tracking error goes as 1 / ki, so the largest ki is
// also about the smallest step IAE: on the quarter car no crossover at the
// same margin tracks the step more than 1 % better (docs/frf-files.md 3).
#pragma once

#include <limits>
#include <optional>
#include <string>

#include "tools/tune/margins.hpp"
#include "tools/tune/plant_grid.hpp"

namespace rigctl {

struct DesignTarget {
  double phase_margin_deg = 60.0;
  std::optional<double> crossover_hz;  // --bandwidth
  double min_gain_margin_db = 6.0;     // classical minimum
  double max_sensitivity = 2.0;        // Ms <= 2: at most 6 dB of disturbance amplification
  // Upper bound on the gain from demand to command (PI kp, P+V+dP Ke): an
  // unfiltered step puts its whole size on the error at once, and a linear
  // design holds only while that does not saturate the valve.
  double max_demand_gain = std::numeric_limits<double>::infinity();
};

struct LoopDesign {
  LoopGains gains;
  Margins margins;      // on the measured plant, with these gains
  bool meets_target = false;
  std::string note;     // why not, when it does not
};

// base: the rig's controller (its kind, period, limits and fixed filters).
// Throws std::runtime_error when no gains reach the target.
LoopDesign design_loop(const PlantGrid& plant, const LoopGains& base, const DesignTarget& target);

// The margins of given gains on the measured plant (the loop as it is).
Margins margins_of(const PlantGrid& plant, const LoopGains& gains);

}  // namespace rigctl
