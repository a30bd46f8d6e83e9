#include "rt/safety/limit_detectors.hpp"

#include <stdexcept>

namespace rigctl {

EventCode event_code(DetectorKind k) {
  switch (k) {
    case DetectorKind::kInvalid: return EventCode::kInputInvalid;
    case DetectorKind::kRange: return EventCode::kLimitTripped;
    case DetectorKind::kRate: return EventCode::kRateLimit;
    case DetectorKind::kTrackingError: return EventCode::kTrackingError;
    case DetectorKind::kValveSaturation: return EventCode::kValveSaturated;
    case DetectorKind::kSampleAge: return EventCode::kSampleStale;
    case DetectorKind::kOverruns: return EventCode::kOverruns;
    case DetectorKind::kOpenCircuit: return EventCode::kOpenCircuit;
    case DetectorKind::kStuck: return EventCode::kSensorStuck;
  }
  return EventCode::kNone;
}

namespace {
bool uses_input(DetectorKind k) {
  switch (k) {
    case DetectorKind::kInvalid:
    case DetectorKind::kRange:
    case DetectorKind::kRate:
    case DetectorKind::kTrackingError:
    case DetectorKind::kOpenCircuit:
    case DetectorKind::kStuck: return true;
    case DetectorKind::kValveSaturation:  // an output
    case DetectorKind::kSampleAge:        // the sample's time stamp
    case DetectorKind::kOverruns: return false;  // the loop's count
  }
  return false;
}
}  // namespace

LimitDetectors::LimitDetectors(std::vector<DetectorSpec> specs, std::size_t input_count, int feedback_input,
                               double period_s)
    : specs_(std::move(specs)), feedback_input_(feedback_input), period_s_(period_s) {
  if (!(period_s > 0.0)) throw std::invalid_argument("limit detectors: period must be positive");
  states_.resize(specs_.size());
  for (std::size_t i = 0; i < specs_.size(); ++i) {
    const auto& s = specs_[i];
    if (uses_input(s.kind) && (s.channel < 0 || static_cast<std::size_t>(s.channel) >= input_count)) {
      throw std::invalid_argument("limit detector '" + s.name + "': input index " + std::to_string(s.channel) +
                                  " out of range");
    }
    if ((s.kind == DetectorKind::kValveSaturation && (s.channel < 0 || s.channel >= static_cast<int>(kMaxOutputs))) ||
        (s.kind == DetectorKind::kStuck && (s.command_output < 0 || s.command_output >= static_cast<int>(kMaxOutputs)))) {
      throw std::invalid_argument("limit detector '" + s.name + "': output index out of range");
    }
    // Durations in whole ticks, at least one: the condition is seen on a tick.
    states_[i].persist_ticks = std::max<int64_t>(1, std::llround(s.duration_s / period_s));
    if (s.kind == DetectorKind::kOverruns) {
      states_[i].ring.assign(static_cast<std::size_t>(std::max<int64_t>(1, std::llround(s.window_s / period_s))), 0);
    }
  }
}

bool LimitDetectors::condition(const DetectorSpec& s, State& st, const DetectorInputs& in, double& value) noexcept {
  const Sample& sample = *in.sample;
  const auto ch = static_cast<std::size_t>(s.channel < 0 ? 0 : s.channel);
  const double x = sample.value[ch < kMaxInputs ? ch : 0];
  const bool x_valid = std::isfinite(x) && ((sample.status >> ch) & 1u) == 0;
  value = x;
  switch (s.kind) {
    case DetectorKind::kInvalid: return !x_valid;
    case DetectorKind::kRange: return x_valid && (x < s.min || x > s.max);
    case DetectorKind::kOpenCircuit: return x_valid && (x <= s.min || x >= s.max);
    case DetectorKind::kRate: {
      if (!x_valid) {
        st.have_previous = false;
        return false;
      }
      const double rate = st.have_previous ? (x - st.previous) / period_s_ : 0.0;
      st.previous = x;
      st.have_previous = true;
      value = rate;
      return std::abs(rate) > s.max;
    }
    case DetectorKind::kTrackingError: {
      value = in.demand - x;
      return in.valve_driven && x_valid && std::abs(value) > s.max;
    }
    case DetectorKind::kValveSaturation: {
      value = in.command != nullptr ? in.command->value[ch] : 0.0;
      return in.valve_driven && std::abs(value) >= s.max;
    }
    case DetectorKind::kSampleAge: {
      if (!st.have_previous || sample.t_ns != st.last_t_ns) {
        st.last_t_ns = sample.t_ns;
        st.fresh_ns = in.now_ns;
        st.have_previous = true;
      }
      value = static_cast<double>(in.now_ns - st.fresh_ns) * 1e-9;
      return value > s.max;
    }
    case DetectorKind::kOverruns: {
      // ring holds the running total at each of the last window ticks.
      const int64_t oldest = st.ring[st.ring_pos];
      st.ring[st.ring_pos] = in.overruns;
      st.ring_pos = (st.ring_pos + 1) % st.ring.size();
      value = static_cast<double>(in.overruns - oldest);
      return in.overruns - oldest > s.max_count;
    }
    case DetectorKind::kStuck: {
      // Counted here, not by persistence: the clock runs only while the valve
      // is commanded hard enough that the sensor must move.
      const double u = in.command != nullptr ? in.command->value[static_cast<std::size_t>(s.command_output)] : 0.0;
      const bool commanded = in.valve_driven && std::abs(u) >= s.command_min;
      if (!x_valid || !st.have_previous || std::abs(x - st.previous) > s.tolerance || !commanded) {
        st.previous = x;
        st.have_previous = x_valid;
        st.count = 0;
        return false;
      }
      return ++st.count >= st.persist_ticks;
    }
  }
  return false;
}

const DetectorResult& LimitDetectors::check(const DetectorInputs& in) noexcept {
  DetectorResult& r = result_;
  r.action = LimitAction::kNone;
  r.faults_present = false;
  r.feedback_invalid = false;
  r.worst_new = DetectorTrip{};
  r.new_count = 0;
  for (std::size_t i = 0; i < specs_.size(); ++i) {
    const DetectorSpec& s = specs_[i];
    State& st = states_[i];
    double value = 0.0;
    bool present = condition(s, st, in, value);
    if (s.kind != DetectorKind::kStuck) {
      st.count = present ? st.count + 1 : 0;
      present = st.count >= st.persist_ticks;
    }
    const bool was_active = st.active;
    st.active = present;
    if (present && s.latch) st.latched = true;
    // Only what stops the rig is a fault; an indication never blocks a reset.
    if (present && s.action >= LimitAction::kHold) r.faults_present = true;
    if (present || st.latched) r.action = more_severe(r.action, s.action);
    if (present && (s.kind == DetectorKind::kInvalid || s.kind == DetectorKind::kOpenCircuit ||
                    s.kind == DetectorKind::kStuck) &&
        (feedback_input_ < 0 || s.channel == feedback_input_)) {
      r.feedback_invalid = true;
    }
    if (present && !was_active) {
      const DetectorTrip trip{event_code(s.kind), static_cast<int16_t>(s.channel), value, s.action,
                              static_cast<uint16_t>(i)};
      if (r.new_count < r.new_trips.size()) r.new_trips[r.new_count] = trip;
      ++r.new_count;
      if (trip.action > r.worst_new.action) r.worst_new = trip;
    }
  }
  return r;
}

int LimitDetectors::clear_latches() noexcept {
  int cleared = 0;
  for (auto& st : states_) {
    if (st.latched && !st.active) {
      st.latched = false;
      ++cleared;
    }
  }
  return cleared;
}

}  // namespace rigctl
