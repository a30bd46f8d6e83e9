// The kinds of limit detector (rt/safety/limit_detectors.hpp) and their
// names: the `type` of a configured detector and the text of messages.
#pragma once

#include <cstdint>
#include <string_view>

namespace rigctl {

enum class DetectorKind : uint8_t {
  kInvalid,          // input not finite or flagged invalid by the driver
  kRange,            // input outside [min, max]
  kRate,             // |d input / dt| > max
  kTrackingError,    // |demand - input| > max while the valve is driven
  kValveSaturation,  // |output| >= max for duration_s while the valve is driven
  kSampleAge,        // the sample time stamp has not advanced for more than max [s]
  kOverruns,         // more than max_count loop overruns within window_s
  kOpenCircuit,      // input at or beyond a rail (<= min or >= max): broken wire, LVDT at its rail
  kStuck,            // input within `tolerance` for duration_s while |output| >= command_min
};

constexpr std::string_view to_string(DetectorKind k) {
  switch (k) {
    case DetectorKind::kInvalid: return "invalid";
    case DetectorKind::kRange: return "range";
    case DetectorKind::kRate: return "rate";
    case DetectorKind::kTrackingError: return "tracking_error";
    case DetectorKind::kValveSaturation: return "valve_saturation";
    case DetectorKind::kSampleAge: return "sample_age";
    case DetectorKind::kOverruns: return "overruns";
    case DetectorKind::kOpenCircuit: return "open_circuit";
    case DetectorKind::kStuck: return "stuck";
  }
  return "unknown";
}

}  // namespace rigctl
