// A test procedure played on the tick: the loop's demand while the rig runs
// (rt/loop/rig_loop.cpp asks it instead of the profile), with its cycle
// counters, compensation, peak-valley change detector and rainflow count.
//
// Every cyclic step begins with an approach: a ramp from where the demand
// stands to the step's start level (not counted). A sine's first cycle then
// brings the amplitude in from zero (a ramp-in cycle, counted apart); block
// programs run valley -> peak -> valley end-level cycles from the first
// row's valley. A start, a resume after a hold and a resume from a recovery
// file all continue the present step this way, at its interrupted cycle.
//
// Compensation (docs/procedures.md):
//  * amplitude_phase: the feedback's fundamental is fitted over two cycles
//    (rt/procedure/sine_fit.hpp); then the command's gain, phase and mean
//    move by `gain` x the error, blended in over the next cycle (no step in
//    the demand), and the two cycles after that are measured.
//  * peak_valley: the feedback's turning points (hysteresis 10 % of the
//    wanted range) against the wanted peak and valley of their row; the row's
//    commanded end levels move by `gain` x the error. Every row keeps its
//    own correction for the program's next pass.
// A correction beyond `max_factor` stops the step (event
// kCompensationLimit, action stop).
//
// Nothing here allocates, locks or waits after construction.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "rt/procedure/procedure_spec.hpp"
#include "rt/procedure/procedure_state.hpp"
#include "rt/procedure/rainflow.hpp"
#include "rt/procedure/sine_fit.hpp"
#include "rt/safety/limit_action.hpp"
#include "rt/sample.hpp"
#include "rt/telemetry_record.hpp"

namespace rigctl {

class ProcedureRunner {
 public:
  // The spec must outlive the runner. Throws std::invalid_argument for a
  // spec the tick cannot play (too many rows, repeats nested too deep,
  // more rainflow channels than kMaxRainflowChannels).
  ProcedureRunner(const ProcedureSpec& spec, double period_s, int feedback_input);

  // Before the run: continue from a recovery (rigctl run --resume).
  void restore(const ProcedureRecovery& recovery) noexcept;

  // The rig starts or resumes running: the present step continues from
  // `present_demand` (an approach ramp), or the procedure begins.
  void start(double present_demand) noexcept;
  // One tick of the procedure while the rig runs: this tick's demand.
  double next(const Sample& sample, double feedback) noexcept;

  bool finished() const noexcept { return state_.status.phase == ProcedurePhase::kDone; }
  // A trip of the procedure's own (peak-valley change, compensation limit):
  // the most severe action since the last reset, and this tick's new one.
  LimitAction action() const noexcept { return action_; }
  bool new_trip(Event& e) const noexcept {
    if (new_trip_.code != EventCode::kNone) e = new_trip_;
    return new_trip_.code != EventCode::kNone;
  }
  void clear_latch() noexcept { action_ = LimitAction::kNone; }

  // An operator's "stop at the end of the block": the procedure runs on to
  // the end of its present block (a block program's or a drive's pass, else
  // the end of the step) and then says so once through take_stop_due(); the loop
  // stops the rig there. The request is in the status (and the recovery)
  // until then.
  void request_stop_at_block_end() noexcept { state_.status.stop_at_block_end = true; }
  // The block an operator asked to stop at has ended: true once (taken; a
  // held or stopped rig does not ask the procedure, so nothing else clears it).
  bool take_stop_due() noexcept {
    const bool due = stop_due_;
    stop_due_ = false;
    return due;
  }

  const ProcedureStatus& status() const noexcept { return state_.status; }
  // A cycle, a pass or a step ended on this tick: a recovery is due.
  bool recovery_due() const noexcept { return recovery_due_; }
  // Fills `out` with everything a resume needs (a copy: no allocation),
  // numbered one after the last; the recovery is no longer due.
  void recovery(ProcedureRecovery& out) noexcept;
  const ProcedureSpec& spec() const noexcept { return spec_; }

 private:
  // What a step's tick gave: a demand, or nothing yet (the step ended
  // without taking time; the next step is asked on the same tick).
  enum class Tick : uint8_t { kDemand, kMoved };

  void enter_step(int index, double present) noexcept;
  void begin_approach(double present) noexcept;
  void begin_cyclic() noexcept;
  void finish_step() noexcept;
  void begin_end_level() noexcept;
  void end_repeat() noexcept;
  Tick approach_tick(double& d) noexcept;
  Tick ramp_tick(double& d) noexcept;
  Tick hold_tick(double& d) noexcept;
  Tick drive_tick(double& d) noexcept;
  Tick sine_tick(const Sample& s, double feedback, double& d) noexcept;
  Tick blocks_tick(const Sample& s, double feedback, double& d) noexcept;
  Tick end_level_tick(double& d) noexcept;
  // A cycle of a cyclic step ended: counts, then whether the step is over.
  bool close_cycle() noexcept;
  void close_sine_cycle() noexcept;
  void track_turning_points(double feedback) noexcept;
  void check_peak_valley(double peak, double valley) noexcept;
  void trip(EventCode code, int channel, double value, LimitAction action) noexcept;
  void track_cycle_extremes(const Sample& s, double feedback) noexcept;
  void count_rainflow(const Sample& s) noexcept;
  // A block (pass or step) ended: a requested stop is due.
  void block_ended() noexcept;
  // Nominal time left: the present step's from its counts, plus the steps
  // after it (after_step_s_, walked when a step begins).
  void update_time_left() noexcept;
  double present_step_left_s() const noexcept;
  double steps_after_s() const noexcept;
  const StepSpec& step() const noexcept { return spec_.steps[static_cast<std::size_t>(state_.status.step)]; }
  const BlockRow& row() const noexcept { return step().rows[static_cast<std::size_t>(state_.status.row)]; }
  std::size_t row_index() const noexcept { return static_cast<std::size_t>(state_.status.row); }

  const ProcedureSpec& spec_;
  double period_s_;
  int feedback_input_;
  ProcedureRecovery state_;
  std::array<RainflowChannel, kMaxRainflowChannels> rainflow_;
  bool started_ = false;
  double last_demand_ = 0.0;
  // approach and end_level ramps
  double ramp_from_ = 0.0, ramp_to_ = 0.0;
  int64_t ramp_ticks_ = 0, ramp_tick_ = 0;
  // cyclic steps: the cycle's phase [0, 1)
  double cycle_phase_ = 0.0;
  // sine: correction blended from `from` to the status' values over a blend cycle
  bool blending_ = false;
  double from_gain_ = 1.0, from_phase_ = 0.0, from_mean_ = 0.0;
  SineFit fit_;
  static constexpr int kMeasuredCycles = 2;
  int measured_cycles_ = 0;  // cycles in the present measurement
  // blocks: the end levels this cycle's halves run between
  double half_start_ = 0.0, half_end_ = 0.0;
  bool in_down_half_ = false;
  // turning points of the feedback (peak_valley)
  int tp_direction_ = 0;
  double tp_extreme_ = 0.0;
  int peak_pending_row_ = -1, valley_pending_row_ = -1;
  // the cycle's extremes of the feedback and of the detector's channel
  double cycle_max_ = 0.0, cycle_min_ = 0.0, pv_max_ = 0.0, pv_min_ = 0.0;
  bool cycle_seen_ = false;
  LimitAction action_ = LimitAction::kNone;
  Event new_trip_{};
  bool recovery_due_ = false;
  bool stop_due_ = false;
  uint64_t sequence_ = 0;
  // Nominal durations, built before the run: each step's (a repeat marker's
  // is 0), each repeat group's body once, and where each group ends.
  std::vector<double> step_time_s_;
  std::vector<double> body_time_s_;
  std::vector<int> group_end_;
  double after_step_s_ = 0.0;
};

}  // namespace rigctl
