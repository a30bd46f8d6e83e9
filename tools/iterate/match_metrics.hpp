// How well a response matches its target, on the band the iteration works
// in (both records band-limited first, on their smoothly padded
// continuation, so drift below the band and noise above it do not count):
// relative RMS error, TRAC (the time-response assurance criterion, the
// squared correlation: 1 for the same shape) and the peak error, over the
// part of the target that carries the test (test_window.hpp), with the
// whole record's relative RMS error beside them.
#pragma once

#include <vector>

#include "tools/iterate/test_window.hpp"

namespace rigctl {

struct MatchMetrics {
  double rel_rms_percent = 0.0;        // 100 rms(e) / rms(target) over the window
  double trac = 0.0;                   // (t . r)^2 / ((t . t)(r . r)), 0..1, over the window
  double peak_error = 0.0;             // max |e| [target unit] over the window
  double rms_error = 0.0;              // [target unit] over the window
  double whole_rel_rms_percent = 0.0;  // 100 rms(e) / rms(target) over the whole record
};

// target and response of equal length at period_s.
MatchMetrics match_metrics(const std::vector<double>& target, const std::vector<double>& response, double period_s,
                           double band_min_hz, double band_max_hz, const TestWindow& window);
// Over the whole record.
MatchMetrics match_metrics(const std::vector<double>& target, const std::vector<double>& response, double period_s,
                           double band_min_hz, double band_max_hz);

}  // namespace rigctl
