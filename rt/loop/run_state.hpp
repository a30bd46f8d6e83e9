// What one run of the loop carries from step to step and from tick to tick.
// The tick's steps (rt/loop/rig_loop.hpp) read and write it explicitly; it
// lives on the loop thread's stack for the run and holds no pointers into
// anything that could allocate.
#pragma once

#include <array>
#include <cstdint>

#include "rt/telemetry_record.hpp"

namespace rigctl {

// The profile's own time: the sample time minus the time the profile was
// not running (before the start, while holding), so a hold freezes the
// profile and a start plays it from its beginning.
struct ProfileClock {
  int64_t first_t_ns = 0;  // the run's first sample time
  int64_t frozen_ns = 0;   // time the profile was not running

  // Start: the profile from its beginning, from this sample on.
  void restart_at(int64_t t_ns) noexcept { frozen_ns = t_ns - first_t_ns; }
  void freeze_for(int64_t ns) noexcept { frozen_ns += ns; }
  double profile_time_s(int64_t t_ns) const noexcept { return static_cast<double>(t_ns - frozen_ns) * 1e-9; }
  double first_s() const noexcept { return static_cast<double>(first_t_ns) * 1e-9; }
};

struct RunState {
  // ---- Where the run is.
  int64_t tick = 0;         // the present tick; after the run, the number of ticks handed off
  int64_t deadline_ns = 0;  // the present tick's wake-up time on the loop's clock
  int feedback_input = 0;   // the controlled input: arm holds it, the record shows it while the valve is safe
  ProfileClock profile_clock;

  // ---- The present tick, filled step by step.
  int64_t woke_ns = 0;      // loop clock at wake-up: the detectors' "now" and the start of the compute time
  TelemetryRecord record;   // handed off at the end of the tick; after the last tick, the base of the closing record
  double feedback = 0.0;    // the controlled input in this tick's sample
  bool valve_enabled = false;  // the valve is driven this tick (after the commands)
  double demand = 0.0;         // this tick's demand; the previous one while the valve is not driven
  // The demands of the control channels after the first (channel i's at
  // i - 1), kept like `demand`: the previous ones while the valve is not driven.
  std::array<double, kMaxChannels - 1> more_demand{};
  Event command_event{};       // this tick's operator or signal command, accepted or refused: the record shows it
  Event procedure_trip{};      // this tick's new trip of the test procedure (peak-valley change, compensation limit)

  int64_t t_ns() const noexcept { return record.sample.t_ns; }  // rig time of this tick's sample

  // ---- The previous tick: what this tick's sample is judged against.
  int64_t previous_t_ns = 0;  // its sample time (the profile clock freezes by the difference)
  double previous_demand = 0.0;
  Command previous_command{};  // zero when the valve was not driven
  bool valve_was_enabled = false;

  // ---- The run so far.
  Event worst_trip{};  // most severe trip since the last reset: hold or worse makes the run a faulted one
  bool ever_ran = false;           // the rig has been running: its coarse state is no longer "starting"
  bool stop_request_seen = false;  // SIGINT/SIGTERM: its stop goes in once, and the run ends when the rig is safe
  bool run_length_reached = false;  // max_ticks: the controlled stop has been asked for
  bool operator_stopped = false;    // operator mode: the operator stopped the rig and has not started it again

  // ---- How the run ends.
  Event end_event{EventCode::kProfileFinished, -1, 0.0};  // why (the closing record and event)
  bool ended_by_fault = false;
};

}  // namespace rigctl
