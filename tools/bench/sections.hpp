// The sections of `rigctl bench`, one per file (tools/bench/<name>.cpp). A
// section is a name, a title and a function from the shared context to its
// JSON result; it prints its own tables to ctx.out. To add one, write its
// function and list it in all_sections() in bench_command.cpp.
//
// JSON convention: every section object has "status": "ok", "skipped" (with
// "reason": why it could not run on this machine), "not_available" (with
// "reason") or "error" (with "error", set by the runner when the section
// throws). Parts of a section follow the same convention.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <ostream>
#include <string>

#include "config/rig_config.hpp"
#include "tools/run/run_command.hpp"
#include "tools/bench/bench_command.hpp"
#include "tools/bench/json.hpp"
#include "tools/bench/reference.hpp"
#include "tools/bench/support.hpp"

namespace rigctl::bench {

struct Context {
  const BenchOptions& options;
  const std::atomic<bool>& stop;
  std::ostream& out;
  ScratchDir& scratch;
  std::string quarter_car_config;  // paths of the shipped configs
  std::string pneumatic_config;

  bool quick() const { return options.quick; }
  // `full` in a full run, `quick` with --quick.
  template <typename T>
  T pick(T full, T quick_value) const {
    return options.quick ? quick_value : full;
  }
};

struct Section {
  std::string name;   // JSON key and --section value
  std::string title;  // console heading
  std::function<Json(Context&)> run;
};

Section timing_section();     // tools/bench/timing.cpp
Section plant_section();      // tools/bench/plant.cpp
Section io_section();         // tools/bench/io.cpp
Section diagnosis_section();  // tools/bench/diagnosis.cpp
Section diagnosis_sweep_section();  // tools/bench/diagnosis.cpp
Section scaling_section();    // tools/bench/scaling.cpp
Section channels_section();   // tools/bench/channels.cpp
Section foxglove_section();   // tools/bench/foxglove.cpp
Section foxglove_limits_section();  // tools/bench/foxglove_limits.cpp
Section procedure_section();  // tools/bench/procedure.cpp

Json skipped(const std::string& reason);

struct LoopRun {
  TimingSummary timing;
  double wall_s = 0.0;
  std::string console;  // what the run printed
};

// `rigctl run CONFIG --duration S` (the quarter car) in-process, on a thread
// of its own so the SCHED_FIFO priority it takes ends with the thread; the
// run log goes to the scratch directory and is removed. `adjust` may change
// the run's options first (tools/bench/timing.cpp).
LoopRun run_loop(Context& ctx, double seconds, const std::string& tag,
                 const std::function<void(RunOptions&)>& adjust = {});

// The commands the configured rig's own closed loop (rig assembly, RigLoop,
// simulated time) puts out over `ticks` periods: what the plant benchmarks
// replay, so that the fixed-step plant and its reference see the same input.
CommandSeries closed_loop_commands(const RigConfig& config, int64_t ticks);

// What the plant benchmarks (plant, scaling) drive the plants with, made
// once per section: the shipped quarter-car and pneumatic configs with
// their closed loops' commands over `seconds` (each at its own period), and
// the half car's passive run at the quarter car's period with its two
// roads. Defined in tools/bench/plant.cpp.
struct PlantInputs {
  PlantInputs(const Context& ctx, double seconds);
  const RigConfig qc;
  const RigConfig pn;
  const double T;        // the quarter car's period, the half car's too
  const int64_t ticks;   // of T over `seconds`
  const CommandSeries qc_u;
  const CommandSeries pn_u;
  const CommandSeries passive;
  HalfCarParams bump;    // the pitch-plane set with the paper's double bump road
  HalfCarParams iso;     // the same on an ISO 8608 class C road
};

}  // namespace rigctl::bench
