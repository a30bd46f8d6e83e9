// The change detector of rig health (docs/rig-health.md 4): a two-sided
// tabular CUSUM (Page 1954) on a parameter standardised by its standard
// deviation, z = (x - reference) / s.
//
// Why CUSUM and not Bayesian on-line change-point detection (Adams & MacKay
// 2007): wear is a slow drift or a step of unknown size away from a known
// commissioning state, in a few hundred points per parameter. CUSUM is the
// optimal detector of a shift of a chosen size from a known reference
// (minimal mean delay for a given false-alarm rate, Lorden 1971), has two
// numbers with textbook meanings (k: half the shift to detect, in sigmas; h:
// the decision threshold, which sets the in-control run length: by
// Siegmund's approximation k = 0.5, h = 5 gives about 940 points between
// false alarms of one side on Gaussian data, 470 for the two-sided chart),
// and its excursion (from its last zero) holds when the change began,
// which is what an alarm must say ("since when"). BOCPD needs a hazard rate
// and a conjugate model of the segments, gives a run-length posterior rather
// than an alarm a technician can reason about, and its cost per point grows
// with the run length unless pruned. Its strength, several change points of
// unknown sign and variance, is not the question here: each parameter has
// one reference and wears one way.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

namespace rigctl::health {

struct CusumSettings {
  double k = 0.5;  // allowance [sigma]: detects shifts of about 2k = 1 sigma and larger
  double h = 5.0;  // decision threshold [sigma]
};

struct CusumAlarm {
  std::size_t raised_at = 0;  // index of the point that crossed h
  std::size_t since = 0;      // where the change began: the likeliest start within the excursion
  int direction = 0;          // +1 rose, -1 fell
  double mean_shift = 0.0;    // mean of x - reference over [since, raised_at], in x's unit (the change's size)
  double mean_shift_sigma = 0.0;  // ... in standard deviations
};

struct CusumPoint {
  double x = 0.0;      // the parameter's value
  double sigma = 0.0;  // its standard deviation (the fit's, widened by the reference's scatter)
};

// Runs the chart over the points against `reference`; one alarm per
// excursion (the side is re-armed once its sum has come back to zero).
// Also returns the upper and lower sums per point for the plot.
struct CusumTrace {
  std::vector<double> upper, lower;
  std::vector<CusumAlarm> alarms;
};
CusumTrace run_cusum(const std::vector<CusumPoint>& points, double reference, const CusumSettings& settings);

}  // namespace rigctl::health
