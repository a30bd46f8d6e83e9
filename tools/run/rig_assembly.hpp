// Builds the parts of a run from a checked config: the driver (with its plant
// when simulated), the controller, the demand profile and the limit checks,
// resolving channel names to indices. Name errors are ConfigErrors that name
// the config key.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "config/rig_config.hpp"
#include "rt/driver.hpp"
#include "plant/simulated_plant.hpp"
#include "rt/control/controller.hpp"
#include "rt/safety/limit_detectors.hpp"
#include "rt/loop/rig_loop.hpp"
#include "rt/control/setpoint_profile.hpp"

namespace rigctl {

struct AssembledRig {
  std::unique_ptr<Driver> driver;
  std::unique_ptr<Controller> controller;
  std::unique_ptr<FilteredProfile> profile;
  LimitDetectors detectors;   // every input's plausibility, `limits:` and `safety.detectors`
  SafetyOptions safety;       // the state machine's settings from `safety:`
  std::string setpoint_name;  // run-file column of the demand, e.g. "x_ref"; "x_ref_1" with several channels
  // The control channels after the first (`channels:`): their controllers,
  // profiles, the loop's view of them and their demands' column names.
  std::vector<std::unique_ptr<Controller>> more_controllers;
  std::vector<std::unique_ptr<FilteredProfile>> more_profiles;
  std::vector<ControlChannel> more_channels;
  std::vector<std::string> more_setpoint_names;  // "x_ref_2", ...
  double profile_duration_s = 0.0;
  int profile_start_input = -1;  // the feedback input the profile starts from, -1: the configured start
};

AssembledRig assemble_rig(const RigConfig& config);

// The configured rig kind's simulated plant (the in-process driver and
// `rigctl rig-sim` both step one).
std::unique_ptr<SimulatedPlant> make_plant(const RigConfig& config);

// The config's demand: its profile through its first-order filter, and the
// profile's natural length.
std::unique_ptr<FilteredProfile> make_profile(const RigConfig& config, double& duration);

// Run-file name of the demand for a rig kind ("x_ref" for quarter_car).
std::string setpoint_name_for(RigKind rig);

}  // namespace rigctl
