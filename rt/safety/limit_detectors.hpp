// Limit detectors on every channel, each with a configured action and latch:
// range, rate, tracking error, valve saturation, sample age, loop overruns,
// and sensor plausibility (not a number / flagged invalid, open circuit at a
// rail, stuck while commanded). Built once at start-up; check() runs on the
// loop thread and never allocates.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "rt/safety/detector_kind.hpp"
#include "rt/safety/limit_action.hpp"
#include "rt/sample.hpp"
#include "rt/telemetry_record.hpp"

namespace rigctl {

EventCode event_code(DetectorKind k);

struct DetectorSpec {
  std::string name;  // config key, for messages (never read on the loop)
  DetectorKind kind = DetectorKind::kRange;
  int channel = -1;  // input index; kValveSaturation: output index; kSampleAge, kOverruns: -1
  double min = -INFINITY;
  double max = INFINITY;
  // The condition must hold this long before it trips (debounce; kStuck and
  // kValveSaturation: the defining duration). 0: on the first tick.
  double duration_s = 0.0;
  double tolerance = 0.0;    // kStuck: changes within this band count as no change
  double command_min = 0.0;  // kStuck: the valve counts as commanded at |output| >= this
  int command_output = 0;    // kStuck: output index of that command
  int64_t max_count = 0;     // kOverruns
  double window_s = 1.0;     // kOverruns
  LimitAction action = LimitAction::kInterlock;
  bool latch = true;  // a latched trip stays until a reset after its condition cleared
};

// What the detectors see on one tick.
struct DetectorInputs {
  const Sample* sample = nullptr;
  int64_t now_ns = 0;           // loop clock at the tick (sample age)
  double demand = 0.0;          // demand acting on this tick (the previous tick's)
  const Command* command = nullptr;  // command acting on this tick (the previous tick's)
  bool valve_driven = false;
  int64_t overruns = 0;         // running total
};

struct DetectorTrip {
  EventCode code = EventCode::kNone;
  int16_t channel = -1;
  double value = 0.0;
  LimitAction action = LimitAction::kNone;
  uint16_t detector = 0;  // index into specs()

  Event event() const { return Event{code, channel, value, 0, static_cast<uint8_t>(action)}; }
};

inline constexpr std::size_t kMaxTripsPerTick = 8;

struct DetectorResult {
  LimitAction action = LimitAction::kNone;  // most severe of active and latched trips
  bool faults_present = false;              // some condition is active now
  bool feedback_invalid = false;            // the feedback input is invalid/at its rail/stuck now
  DetectorTrip worst_new;                   // first of the most severe trips new this tick
  std::array<DetectorTrip, kMaxTripsPerTick> new_trips{};  // trips new this tick, in check order
  std::size_t new_count = 0;                // may exceed kMaxTripsPerTick; only that many kept
};

class LimitDetectors {
 public:
  LimitDetectors() = default;
  // feedback_input: the controlled input (its plausibility decides whether the
  // valve may be driven); -1: every input. period_s turns durations into ticks.
  LimitDetectors(std::vector<DetectorSpec> specs, std::size_t input_count, int feedback_input, double period_s);


  // Loop thread. Updates every detector and returns this tick's summary.
  const DetectorResult& check(const DetectorInputs& in) noexcept;
  // Loop thread. A successful reset: latches of trips whose condition has
  // gone are cleared. Returns the number cleared.
  int clear_latches() noexcept;

  const std::vector<DetectorSpec>& specs() const { return specs_; }
  const DetectorResult& last() const { return result_; }

 private:
  struct State {
    int64_t persist_ticks = 1;   // ticks the condition must hold
    int64_t count = 0;           // consecutive ticks it held
    bool active = false;         // tripped and condition still present
    bool latched = false;
    bool have_previous = false;
    double previous = 0.0;       // kRate: last value; kStuck: reference value
    int64_t fresh_ns = 0;        // kSampleAge: loop time the time stamp last advanced
    int64_t last_t_ns = 0;
    std::vector<int64_t> ring;   // kOverruns: totals over the window (sized at construction)
    std::size_t ring_pos = 0;
  };
  // Is the condition present this tick; `value` is what is reported.
  bool condition(const DetectorSpec& s, State& st, const DetectorInputs& in, double& value) noexcept;

  std::vector<DetectorSpec> specs_;
  std::vector<State> states_;
  int feedback_input_ = -1;
  double period_s_ = 0.0025;
  DetectorResult result_;
};

}  // namespace rigctl
