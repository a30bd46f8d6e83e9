// The rig's standard step test and how its result is judged: the config's
// ramp_steps profile (the quarter car: ramp to mid-stroke, then 50 mm steps
// through the demand filter; the pneumatic servo: a 0.8 rad step), its first
// step that moves the demand, and the integrated absolute tracking error
// from that step to the end. The same numbers for a prediction and for a
// measured run.
#pragma once

#include <string>
#include <vector>

#include "config/rig_config.hpp"

namespace rigctl {

struct StepTest {
  double step_time_s = 0.0;  // profile time of the first step that moves the demand
  double step = 0.0;         // its size [feedback unit]
  double target = 0.0;       // the demand it steps to
  double window_end_s = 0.0; // the next step's time (the first step's response ends there)
  double end_s = 0.0;        // the profile's end
};

// Throws std::invalid_argument when the config's profile is not ramp_steps.
StepTest standard_step(const RigConfig& config);

struct StepMetrics {
  double overshoot = 0.0;   // largest excursion past the target, fraction of |step|
  double settling_s = 0.0;  // from the step until the response stays within 2 % of |step| of the target
  double iae = 0.0;         // integral of |demand - response| from the step to the end [unit s]
};

// t: profile (or run) time with the step at test.step_time_s + t_offset.
StepMetrics step_metrics(const StepTest& test, const std::vector<double>& t, const std::vector<double>& demand,
                         const std::vector<double>& response, double t_offset = 0.0);

// The standard step's metrics of a run of the config (a run file: `rigctl
// run --csv`), the profile's time starting with the first driven tick.
StepMetrics measured_step(const RigConfig& config, const std::string& run_file);

}  // namespace rigctl
