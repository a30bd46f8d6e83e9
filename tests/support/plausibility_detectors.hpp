// The limit detectors rig assembly puts on every rig before any configured
// limit (tools/run/rig_assembly.cpp): each input's plausibility (not a
// number, or flagged invalid by the driver), an interlock. For closed-loop
// tests that build their plant and controller without a config file.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "rt/safety/limit_detectors.hpp"

namespace rigctl::test {

inline LimitDetectors plausibility_detectors(std::size_t input_count, int feedback_input, double period_s) {
  std::vector<DetectorSpec> specs;
  for (std::size_t i = 0; i < input_count; ++i) {
    DetectorSpec s;
    s.name = "invalid." + std::to_string(i);
    s.kind = DetectorKind::kInvalid;
    s.channel = static_cast<int>(i);
    specs.push_back(s);
  }
  return LimitDetectors(std::move(specs), input_count, feedback_input, period_s);
}

}  // namespace rigctl::test
