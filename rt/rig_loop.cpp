#include "rt/rig_loop.hpp"

namespace rigctl {

RigLoop::RigLoop(Driver& driver, Controller& controller, FilteredProfile& profile, const LimitCheck& limits,
                 TelemetrySink& telemetry, LoopClock& clock, const LoopOptions& options)
    : driver_(driver), controller_(controller), profile_(profile), limits_(limits), telemetry_(telemetry),
      clock_(clock), options_(options), timing_(options.period_ns, options.overrun_policy) {}

void RigLoop::emit(TelemetryRecord& record, bool with_timing) noexcept {
  record.has_timing = with_timing;
  if (with_timing) record.timing = timing_.summary();
  if (!telemetry_.push(record)) ++dropped_;
}

LoopResult RigLoop::run(const std::atomic<bool>& stop_requested) {
  LoopResult result;
  TelemetryRecord record;
  controller_.reset();
  profile_.reset();

  int64_t deadline = clock_.now_ns();
  int64_t tick = 0;
  Event end_event{EventCode::kProfileFinished, -1, 0.0};
  RigState end_state = RigState::kStopped;

  try {
    for (; tick < options_.max_ticks; ++tick) {
      clock_.sleep_until(deadline);
      const int64_t start = clock_.now_ns();
      timing_.on_wake(deadline, start);

      if (stop_requested.load(std::memory_order_relaxed)) {
        end_event = Event{EventCode::kStopRequested, -1, 0.0};
        break;
      }

      record = TelemetryRecord{};
      record.tick = tick;
      record.state = RigState::kRunning;
      if (tick == 0) record.event = Event{EventCode::kRunStarted, -1, 0.0};

      if (!driver_.read(record.sample)) {
        end_event = Event{EventCode::kDriverReadFailed, -1, 0.0};
        end_state = RigState::kFaulted;
        break;
      }
      const Event violation = limits_.check(record.sample);
      if (violation.code != EventCode::kNone) {
        driver_.make_safe();
        end_event = violation;
        end_state = RigState::kFaulted;
        break;
      }

      if (tick == 0 && options_.start_from_input >= 0) {
        profile_.start_from(record.sample.value[static_cast<std::size_t>(options_.start_from_input)]);
      }
      const double setpoint = profile_.next(static_cast<double>(record.sample.t_ns) * 1e-9);
      controller_.update(setpoint, record.sample, record.command, record.controller);
      driver_.write(record.command);

      const int64_t end = clock_.now_ns();
      deadline = timing_.on_done(deadline, start, end);
      const bool timing_due = options_.timing_every_ticks > 0 && (tick + 1) % options_.timing_every_ticks == 0;
      emit(record, timing_due);
    }
  } catch (...) {
    // Drivers may throw on a broken device; the outputs go safe before the
    // exception leaves the loop.
    driver_.make_safe();
    throw;
  }
  driver_.make_safe();

  // The closing record: why the run ended, and the final timing statistics.
  record.tick = tick;
  record.has_sample = false;
  record.state = end_state;
  record.event = end_event;
  emit(record, true);

  result.ticks = tick;
  result.final_state = end_state;
  result.end_event = end_event;
  result.timing = timing_.summary();
  result.dropped_records = dropped_;
  return result;
}

}  // namespace rigctl
