// The part of a target that carries the test, and the weight the drive's
// corrections get along the record.
//
// A lab's target starts at home, ramps to the operating point, holds, then
// carries the road; it ends the other way round. The error that counts is
// the one over the road part (a slow 80 mm ramp tracked well would dilute
// the error of a 3 mm road), and the drive's ends must follow the target's
// own lead-in and lead-out: at home the drive is the target itself, so
// neither the inverse's non-causal ringing nor a static gain below one can
// take it out of the stroke before the rig has moved.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace rigctl {

struct TestWindow {
  std::size_t begin = 0, end = 0;  // samples [begin, end)
  std::string source;              // "lead-in/lead-out", "--window", "whole record"
};

// Where the target departs from its lead-in and lead-out: the first and the
// last sample whose content above a few hertz (where a ramp has next to
// nothing and a road has most of its motion) reaches a share of its
// largest; the whole record for a target whose content starts at once.
TestWindow find_test_window(const std::vector<double>& target, double dt);

// "T0:T1" [s] as given to --window; throws std::invalid_argument naming it.
std::pair<double, double> parse_time_window(const std::string& text);

// [t0_s, t1_s) of a record of n samples at dt; throws std::invalid_argument
// naming --window when it is empty or outside the record.
TestWindow window_from_times(double t0_s, double t1_s, std::size_t n, double dt);

// The weight of the drive's corrections per sample: 0 while the target
// holds its first value (at home the drive is the target itself) and from
// where it last leaves its final value, 1 from `lead_s` before the window
// to `lead_s` after it, a half cosine in between over at least
// `min_ramp_s` (so a window at the record's start still gets a smooth fade).
std::vector<double> correction_weight(const TestWindow& window, const std::vector<double>& target, double dt,
                                      double lead_s, double min_ramp_s);

}  // namespace rigctl
