// The standard step test predicted for a design: the fitted plant model
// (tools/tune/plant_fit.hpp) driven, tick by tick, by the rig's own
// controller class (rt/control) with the tuned gains and its output limit,
// following the config's own demand profile. The model is linear about the
// operating point, held there by the command the identification measured.
#pragma once

#include <vector>

#include "config/rig_config.hpp"
#include "tools/tune/loop_gains.hpp"
#include "tools/tune/plant_fit.hpp"
#include "tools/tune/step_test.hpp"

namespace rigctl {

struct StepPrediction {
  StepTest test;
  StepMetrics metrics;
  std::vector<double> t, demand, response;  // profile time
};

// hold_command: the valve command that holds the operating point.
StepPrediction predict_step(const PlantModel& model, const LoopGains& gains, const RigConfig& config,
                            double hold_command);

}  // namespace rigctl
