// `rigctl compare`: the half car's passive suspension and its three active
// controllers (the paper's fuzzy controller, skyhook and LQR as baselines)
// on the configured road, each run through the same assembly and loop as
// `rigctl run --fast` (simulated driver with its sensor models, 2.5 ms
// loop, virtual clock). Prints the metrics table and our reductions beside
// seed 001's, with a short account of the differences; writes each run's
// CSV (run-file format, half_car columns, plant truth) and a metrics JSON.
#pragma once

#include <array>
#include <ostream>
#include <string>
#include <vector>

#include "config/rig_config.hpp"
#include "rt/loop/rig_loop.hpp"
#include "tools/suspension/suspension_metrics.hpp"

namespace rigctl {

// One closed-loop run of the half car, recorded on every tick from the
// plant's true (noise-free) signals; the loop itself saw the sensor models.
struct SuspensionRecording {
  std::string controller;              // passive | fuzzy | skyhook | lqr
  LoopResult loop;
  std::vector<std::string> signal_names;  // the plant's signals() (run-file names first)
  std::vector<std::string> output_names;  // f_1, f_2
  std::string setpoint_name;              // z_s_ref
  std::vector<double> t;                  // [s] sample time
  std::vector<double> setpoint;           // [m]
  std::vector<std::vector<double>> command;  // per tick: the controller's outputs [N]
  std::vector<std::vector<double>> truth;    // per tick: the plant's signals
  SuspensionRun run;                      // the metric inputs, from truth (forces: the commands)
  std::array<double, 2> least_tyre_load{};      // [N] smallest total tyre load per wheel
  std::array<double, 2> peak_applied_force{};   // [N] largest |force| the plant applied per actuator
};

// When the road's disturbance begins [s]: the bump's start, the curve's
// entry, 0 for the random road.
double half_car_disturbance_start(const HalfCarParams& p);

// Runs `controller_type` on the config (its plant, road, sensors, loop) for
// duration_s of simulated time. keep_rows = false keeps only `run` (the
// optimiser's evaluations). Throws ConfigError for a config that cannot be
// assembled, std::runtime_error for a rig that is not a simulated half car.
SuspensionRecording run_half_car(const RigConfig& config, ControllerKind controller_type, double duration_s,
                                 bool keep_rows = true);

// Writes a recording as a run file (docs/run-files.md): metadata
// lines, then t, the setpoint, the outputs, every plant signal.
void write_recording_csv(const SuspensionRecording& rec, const std::string& path, const std::string& note);

// The paper's passive-vs-active figures (seed 001, results and conclusion).
struct PaperFigures {
  double peak_body_displacement_reduction = 74.2;   // [%] "passenger bounce" / vertical shift peak (Fig. 6)
  double peak_body_acceleration_reduction = 88.72;  // [%] sprung mass acceleration
  double peak_tyre_deflection_reduction = 28.5;     // [%] tyre displacement (Figs. 18-21)
  double settling_passive_s = 6.0;                  // [s] Fig. 6
  double settling_active_s = 3.5;
  double roll_acceleration_reduction = 65.0;        // [%] Fig. 12
  double lqr_wk_passive = 0.2834;                   // [m/s^2] sprung mass weighted RMS (LQR, in the text)
  double lqr_wk_active = 0.0492;
};

struct CompareOptions {
  std::string config_path;
  std::string case_name;  // a `cases:` entry, "" for none
  std::string out_dir;    // default: <telemetry.log_dir>/half_car-compare[-CASE]
};

struct CompareResult {
  std::vector<SuspensionRecording> runs;  // passive, fuzzy, skyhook, lqr
  std::vector<SuspensionMetrics> metrics;
  double settling_band = 0.0;             // [m]
  std::string out_dir;
  std::string json_path;
  std::vector<std::string> csv_paths;
};

// Throws ConfigError (exit 2) or std::runtime_error.
CompareResult run_compare(const CompareOptions& options, std::ostream& out);

}  // namespace rigctl
