// Where a test procedure is (rt/procedure/procedure_runner.hpp), as plain
// fixed-size data: the telemetry record carries it every tick and a
// recovery file holds it. Copying it never allocates.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

namespace rigctl {

inline constexpr int kMaxRepeatDepth = 4;  // `repeat` groups nested at most this deep

enum class ProcedurePhase : uint8_t {
  kApproach,  // ramping from where the actuator stands to the step's start level (not counted)
  kRampIn,    // a sine's first cycle, its amplitude from 0 (counted apart)
  kRun,       // the step proper: its cycles are test cycles
  kEndLevel,  // ramping to the step's end_level
  kDone,      // the procedure has ended
};

constexpr std::string_view to_string(ProcedurePhase p) {
  switch (p) {
    case ProcedurePhase::kApproach: return "approach";
    case ProcedurePhase::kRampIn: return "ramp_in";
    case ProcedurePhase::kRun: return "run";
    case ProcedurePhase::kEndLevel: return "end_level";
    case ProcedurePhase::kDone: return "done";
  }
  return "unknown";
}

struct ProcedureStatus {
  bool active = false;  // a procedure runs this run (else the rest is zero)
  int32_t step = 0;     // index into ProcedureSpec::steps
  ProcedurePhase phase = ProcedurePhase::kApproach;
  int64_t step_cycles = 0;     // test cycles done in this step (sine/block cycles, drive passes)
  int64_t total_cycles = 0;    // test cycles done in the whole procedure
  int64_t ramp_in_cycles = 0;  // cycles run to bring the amplitude in, never test cycles
  int32_t row = 0;             // blocks: the present row
  int64_t row_cycles = 0;      // blocks: cycles done in this row in this pass
  int64_t pass = 0;            // blocks, drive: passes of the program done
  int32_t repeat_depth = 0;    // open `repeat` groups
  std::array<int32_t, kMaxRepeatDepth> repeat_begin{};  // each open group's kRepeatBegin step
  std::array<int64_t, kMaxRepeatDepth> repeat_done{};   // each open group's passes done
  int64_t step_ticks = 0;      // ramp, hold, drive: ticks into the step (drive: into the pass)
  double level = 0.0;          // ramp: its start; hold: its level
  double wanted = 0.0;         // the programmed demand this tick, before compensation
  // The compensation as it stands (sine: gain, phase [rad], mean offset;
  // peak_valley: the present row's commanded peak and valley).
  double comp_gain = 1.0;
  double comp_phase = 0.0;
  double comp_mean = 0.0;
  double comp_peak = 0.0;
  double comp_valley = 0.0;
  // The last measured cycle: sine: the fundamental's amplitude error
  // (fraction) and phase error [rad]; peak_valley: the last feedback peak's
  // and valley's errors (fractions of the wanted range); both: the feedback's
  // peak and valley.
  double amplitude_error = 0.0;
  double phase_error = 0.0;
  double peak_error = 0.0;
  double valley_error = 0.0;
  double peak = 0.0;
  double valley = 0.0;
  double damage = 0.0;  // pseudo-damage of the first rainflow channel (committed)
  // The peak-valley change detector's last cycle against its reference
  // (fraction of the reference range; 0 until the reference is taken): its
  // trend is the specimen's.
  double pv_change = 0.0;
  // Nominal time to the procedure's end [s] at the programmed frequencies
  // and times: approaches, end-level ramps and holds by an operator not counted.
  double time_left_s = 0.0;
  // An operator asked to stop at the end of the present block (a block
  // program's or a drive's pass, else the step); cleared when it stops.
  bool stop_at_block_end = false;
};

}  // namespace rigctl
