// Shared steps of the commissioning tests (rigctl identify and tune, issue
// 18): runs of the program in a test's folder, the standard step test's
// metrics from a run file, and the margins of a loop measured with an FRF.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "config/config_reader.hpp"
#include "process.hpp"
#include "tools/identify/frf_file.hpp"
#include "tools/tune/loop_design.hpp"
#include "tools/tune/step_test.hpp"

namespace rigctl::test {

// A fresh folder for one test (nothing left from an earlier run).
inline std::string commissioning_dir(const std::string& name) {
  const auto dir = std::filesystem::path(::testing::TempDir()) / ("commissioning-" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

// A config written into a test's folder; returns its path.
inline std::string write_config(const std::string& dir, const std::string& name, const std::string& text) {
  const std::string path = dir + "/" + name;
  std::ofstream(path) << text;
  return path;
}

inline ProcessResult rigctl(const std::string& args) { return run_command(std::string(RIGCTL_BINARY) + " " + args); }

// The config's standard step test run in simulated time; metrics against the
// profile's own timing (the profile starts with the first driven tick).
inline StepMetrics run_step_test(const std::string& config, const std::string& dir, const std::string& tag) {
  const std::string csv = dir + "/" + tag + "-step.csv";
  const auto r = rigctl("run " + config + " --fast --csv " + csv + " --log " + dir + "/" + tag + "-step.lcm");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return measured_step(load_rig_config(config), csv);
}

// The position loop of the config's gains on a measured plant.
inline Margins measured_margins(const std::string& frf_path, const std::string& config) {
  const FrfData frf = read_frf_file(frf_path);
  return margins_of(PlantGrid(PlantResponse::from_frf(frf)), LoopGains::from_config(load_rig_config(config)));
}

// The same loop straight from the measured closed loop, L = T / (1 - T).
inline Margins closed_loop_margins(const std::string& frf_path) { return rigctl::closed_loop_margins(read_frf_file(frf_path)); }

inline double gain_of(const std::string& config, const std::string& key) {
  return LoopGains::from_config(load_rig_config(config)).config_values().at(key);
}

}  // namespace rigctl::test
