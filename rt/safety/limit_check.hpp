// Per-tick plausibility and range checks on the inputs (the config's
// `limits:`). The first violation found is reported as an event. Nothing on
// the loop uses it any more: rig assembly turns `limits:` into range
// detectors (rt/safety/limit_detectors.hpp) beside the `safety:` ones. Only
// AssembledRig::limits still builds one; this header goes with that field.
#pragma once

#include <cmath>
#include <vector>

#include "rt/sample.hpp"
#include "rt/telemetry_record.hpp"

namespace rigctl {

struct InputLimit {
  int input = -1;  // index in the sample
  double min = -INFINITY;
  double max = INFINITY;
};

class LimitCheck {
 public:
  LimitCheck() = default;
  // Every input is checked for NaN/invalid; listed inputs also for range.
  LimitCheck(std::vector<InputLimit> limits, std::size_t input_count)
      : limits_(std::move(limits)), input_count_(input_count) {}

  Event check(const Sample& s) const noexcept {
    for (std::size_t i = 0; i < input_count_; ++i) {
      if (!std::isfinite(s.value[i]) || (s.status >> i) & 1u) {
        return Event{EventCode::kInputInvalid, static_cast<int16_t>(i), s.value[i]};
      }
    }
    for (const auto& l : limits_) {
      const double v = s.value[static_cast<std::size_t>(l.input)];
      if (v < l.min || v > l.max) return Event{EventCode::kLimitTripped, static_cast<int16_t>(l.input), v};
    }
    return Event{};
  }

  const std::vector<InputLimit>& limits() const { return limits_; }
  std::size_t input_count() const { return input_count_; }

 private:
  std::vector<InputLimit> limits_;
  std::size_t input_count_ = 0;
};

}  // namespace rigctl
