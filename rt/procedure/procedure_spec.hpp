// A test procedure as plain data: what config/procedure_config.cpp reads
// from a procedure file (docs/procedures.md) and ProcedureRunner plays on
// the tick. Built once before the run; the runner only reads it.
//
// The steps are a flat list: `repeat` is a kRepeatBegin ... kRepeatEnd pair
// (nested at most kMaxRepeatDepth deep), so the runner walks an index and a
// small stack of repeat counters, and a recovery file holds both.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "rt/procedure_status.hpp"
#include "rt/safety/limit_action.hpp"

namespace rigctl {

enum class StepKind : uint8_t {
  kRamp,         // to `level` at `rate` (or within `time_s`)
  kHold,         // the present level for `time_s`
  kSine,         // mean + amplitude sin(2 pi f t), `cycles` cycles
  kBlocks,       // rows of (mean, amplitude, frequency, cycles), the program `repeats` times
  kDrive,        // a drive time history (rigctl iterate), played `repeats` times
  kRepeatBegin,  // the steps up to the matching kRepeatEnd, `repeats` times
  kRepeatEnd,
};

constexpr std::string_view to_string(StepKind k) {
  switch (k) {
    case StepKind::kRamp: return "ramp";
    case StepKind::kHold: return "hold";
    case StepKind::kSine: return "sine";
    case StepKind::kBlocks: return "blocks";
    case StepKind::kDrive: return "drive";
    case StepKind::kRepeatBegin: return "repeat";
    case StepKind::kRepeatEnd: return "repeat_end";
  }
  return "unknown";
}

enum class Compensation : uint8_t {
  kNone,
  kAmplitudePhase,  // per cycle: the fundamental's amplitude, phase and mean corrected (sine)
  kPeakValley,      // per cycle and level: the command's end levels corrected (sine, blocks)
};

constexpr std::string_view to_string(Compensation c) {
  switch (c) {
    case Compensation::kNone: return "none";
    case Compensation::kAmplitudePhase: return "amplitude_phase";
    case Compensation::kPeakValley: return "peak_valley";
  }
  return "unknown";
}

struct BlockRow {
  double mean = 0.0;
  double amplitude = 0.0;
  double frequency_hz = 1.0;
  int64_t cycles = 1;
};

struct CompensationSpec {
  Compensation kind = Compensation::kNone;
  // Fraction of the measured error corrected per update. Below 1 the
  // correction approaches the wanted value from one side (no overshoot) as
  // long as the rig's incremental gain (d log response / d log command) is
  // below 1/gain: 0.7 allows 1.4, more than the quarter car's friction gives
  // (docs/procedures.md).
  double gain = 0.7;
  // A correction beyond this factor of the wanted amplitude (or range), or
  // below its inverse, stops the step: something broke or came loose.
  double max_factor = 3.0;
};

// Peaks and valleys of `channel` per cycle against the reference taken at
// the step's start (the mean of `reference_cycles` cycles after
// `settle_cycles`): beyond `tolerance` (a fraction of the reference range)
// for `cycles` cycles in a row, `action`.
struct PeakValleyDetectorSpec {
  bool enabled = false;
  int channel = -1;  // input index
  int64_t settle_cycles = 20;   // compensation has converged by then (docs/procedures.md)
  int64_t reference_cycles = 5;
  double tolerance = 0.05;
  int64_t cycles = 3;
  LimitAction action = LimitAction::kHold;
};

struct StepSpec {
  StepKind kind = StepKind::kHold;
  std::string name;  // "steps[2]" or its `name:`; messages and the log
  // ramp
  double level = 0.0;
  double rate = 0.0;    // [unit/s], > 0 (ramp, end_level, the approach to a cyclic step)
  double time_s = 0.0;  // ramp (when rate is 0) and hold
  // sine (one row) and blocks (several)
  std::vector<BlockRow> rows;
  int64_t repeats = 1;  // blocks, drive, repeat
  CompensationSpec compensation;
  PeakValleyDetectorSpec peak_valley;
  // drive: the demand at the loop's period, read from drive_path's
  // drive_column (a run file; tools/procedure/procedure_loader.hpp)
  std::vector<double> drive;
  std::string drive_path;
  std::string drive_column;
  // Where the actuator goes after the step, ramped at the procedure's ramp rate.
  double end_level = 0.0;
  bool has_end_level = false;
};

// Data capture (docs/procedures.md, "Capture"): written off the tick by
// tools/procedure/capture_writer.hpp from the telemetry the tick already
// hands over; the runner never looks at it.
struct CaptureSpec {
  bool enabled = false;
  std::vector<int> channels;         // input indices: their peak and valley every test cycle
  bool log_spaced_histories = true;  // full-rate histories of each step's cycles 1, 2, 5, 10, 20, 50, ...
  double pre_trigger_s = 0.5;        // around every trip: this long before
  double post_trigger_s = 0.5;       // and this long after
};

struct ProcedureSpec {
  std::string path;       // the file it came from
  std::string hash;       // FNV-1a of its bytes, hex: a recovery file names the procedure it belongs to
  std::vector<StepSpec> steps;
  double ramp_rate = 0.01;  // [unit/s] default ramp, end_level and approach rate (10 mm/s: a slow, safe move)
  // Rainflow: which inputs are counted, with the Basquin exponent and the
  // reference range of the pseudo-damage.
  std::vector<int> rainflow_channels;
  double basquin_exponent = 5.0;
  double reference_range = 0.0;  // 0: the first programmed amplitude's range
  CaptureSpec capture;
  // Total test cycles the procedure programs (sine and block cycles, drive
  // passes), repeats included.
  int64_t programmed_cycles() const;
};

}  // namespace rigctl
