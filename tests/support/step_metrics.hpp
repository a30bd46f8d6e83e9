// Step- and ramp-response metrics computed from a sampled response, for the
// closed-loop tests. Header only; no dependency on the project.
//
// A pneumatic position loop with hysteresis often oscillates *below* its
// final value (the arm runs forward, stops, runs forward again) without ever
// crossing it, so oscillation is counted from the reversals of the response
// (a zigzag detector with a threshold), not from crossings of the final value.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace rigctl::step_metrics {

// A sampled response y(t), times increasing.
struct Response {
  std::vector<double> t;
  std::vector<double> y;
};

struct Extremum {
  double t = 0.0;
  double y = 0.0;
};

struct StepMetrics {
  double step = 0.0;                // demand change [unit]
  double final_value = 0.0;         // mean over the final window
  double steady_state_error = 0.0;  // demand - final value
  double overshoot = 0.0;           // largest excursion past the demand, fraction of |step|
  double rise_time = NAN;           // 10 % -> 90 % of the way to the final value [s]
  double settling_time = 0.0;       // last exit from final value +- band x |step|, from the step [s]
  int reversals = 0;                // direction changes with a retrace > swing threshold
  double oscillations = 0.0;        // reversals / 2: full cycles
  double frequency = NAN;           // from the mean time between reversals [Hz] (NaN with < 2)
  double first_swing = NAN;         // |y(rev 2) - y(rev 1)|: the first back-swing [unit]
  double swing_decay = NAN;         // mean ratio of swings one cycle apart (NaN with < 3 swings)
  std::vector<Extremum> extrema;    // the reversal points, in order
};

// Mean of y over [t0, t1].
inline double mean_over(const Response& r, double t0, double t1) {
  double sum = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < r.t.size(); ++i) {
    if (r.t[i] >= t0 && r.t[i] <= t1) {
      sum += r.y[i];
      ++n;
    }
  }
  return n > 0 ? sum / n : NAN;
}

// Largest |y - ref| over [t0, t1].
inline double max_deviation(const Response& r, double ref, double t0, double t1) {
  double m = 0.0;
  for (std::size_t i = 0; i < r.t.size(); ++i) {
    if (r.t[i] >= t0 && r.t[i] <= t1) m = std::max(m, std::abs(r.y[i] - ref));
  }
  return m;
}

// max - min of y over [t0, t1].
inline double peak_to_peak(const Response& r, double t0, double t1) {
  double lo = INFINITY, hi = -INFINITY;
  for (std::size_t i = 0; i < r.t.size(); ++i) {
    if (r.t[i] >= t0 && r.t[i] <= t1) {
      lo = std::min(lo, r.y[i]);
      hi = std::max(hi, r.y[i]);
    }
  }
  return hi >= lo ? hi - lo : NAN;
}

// Reversal points of y over [t0, t1] starting in direction `dir` (+1/-1): an
// extreme is confirmed once y has retraced from it by more than `threshold`.
inline std::vector<Extremum> reversals(const Response& r, double t0, double t1, int dir, double threshold) {
  std::vector<Extremum> out;
  bool started = false;
  Extremum ext;
  for (std::size_t i = 0; i < r.t.size(); ++i) {
    if (r.t[i] < t0 || r.t[i] > t1) continue;
    if (!started) {
      ext = {r.t[i], r.y[i]};
      started = true;
      continue;
    }
    if (dir * (r.y[i] - ext.y) > 0.0) {
      ext = {r.t[i], r.y[i]};
    } else if (dir * (ext.y - r.y[i]) > threshold) {
      out.push_back(ext);
      dir = -dir;
      ext = {r.t[i], r.y[i]};
    }
  }
  return out;
}

// Response to a step of the demand from `start` to `target` at t_step,
// analysed up to t_end. band: fraction of |step| for settling. swing: the
// retrace, as a fraction of |step|, that makes a reversal. final_window [s]:
// the final value is the mean over [t_end - final_window, t_end].
inline StepMetrics analyse_step(const Response& r, double t_step, double start, double target, double t_end,
                                double band = 0.05, double swing = 0.01, double final_window = 0.5) {
  StepMetrics m;
  m.step = target - start;
  const int dir = m.step >= 0.0 ? 1 : -1;
  const double size = std::abs(m.step);
  m.final_value = mean_over(r, t_end - final_window, t_end);
  m.steady_state_error = target - m.final_value;

  double peak = -INFINITY;
  double t10 = NAN, t90 = NAN;
  const double travel = m.final_value - start;
  for (std::size_t i = 0; i < r.t.size(); ++i) {
    if (r.t[i] < t_step || r.t[i] > t_end) continue;
    peak = std::max(peak, dir * (r.y[i] - target));
    const double f = travel != 0.0 ? (r.y[i] - start) / travel : 0.0;
    if (std::isnan(t10) && f >= 0.1) t10 = r.t[i];
    if (std::isnan(t90) && f >= 0.9) t90 = r.t[i];
    if (std::abs(r.y[i] - m.final_value) > band * size) m.settling_time = r.t[i] - t_step;
  }
  m.overshoot = std::max(0.0, peak) / size;
  m.rise_time = t90 - t10;

  m.extrema = reversals(r, t_step, t_end, dir, swing * size);
  m.reversals = static_cast<int>(m.extrema.size());
  m.oscillations = 0.5 * m.reversals;
  if (m.extrema.size() >= 2) {
    const double half_period = (m.extrema.back().t - m.extrema.front().t) / (m.extrema.size() - 1);
    m.frequency = 0.5 / half_period;
    m.first_swing = std::abs(m.extrema[1].y - m.extrema[0].y);
  }
  std::vector<double> swings;
  for (std::size_t i = 1; i < m.extrema.size(); ++i) swings.push_back(std::abs(m.extrema[i].y - m.extrema[i - 1].y));
  double sum = 0.0;
  int n = 0;
  for (std::size_t i = 2; i < swings.size(); ++i) {
    sum += swings[i] / swings[i - 2];
    ++n;
  }
  if (n > 0) m.swing_decay = sum / n;
  return m;
}

// Total motion against `dir` over [t0, t1]: how far the response ran back.
// Zero for a response that approaches monotonically, however slowly.
inline double reverse_travel(const Response& r, double t0, double t1, int dir) {
  double back = 0.0;
  for (std::size_t i = 1; i < r.t.size(); ++i) {
    if (r.t[i - 1] < t0 || r.t[i] > t1) continue;
    back += std::max(0.0, -dir * (r.y[i] - r.y[i - 1]));
  }
  return back;
}

// Frequency [Hz] of an oscillation from the mean time between its reversals
// (retrace > threshold) over [t0, t1]; NaN with fewer than two reversals.
inline double reversal_frequency(const Response& r, double t0, double t1, double threshold) {
  const auto ext = reversals(r, t0, t1, 1, threshold);
  if (ext.size() < 2) return NAN;
  return 0.5 * (ext.size() - 1) / (ext.back().t - ext.front().t);
}

// Exponential decay rate [1/s] of an oscillation over [t0, t1]: the
// peak-to-peak of y in consecutive windows of length `window` (at least one
// period), fitted by least squares as pp ~ exp(-rate t). Positive = decaying.
inline double decay_rate(const Response& r, double t0, double t1, double window) {
  double sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0;
  int n = 0;
  for (double a = t0; a + window <= t1 + 1e-9; a += window) {
    const double pp = peak_to_peak(r, a, a + window);
    if (!(pp > 0.0)) continue;
    const double x = a + 0.5 * window, y = std::log(pp);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    ++n;
  }
  if (n < 2) return NAN;
  return -(n * sxy - sx * sy) / (n * sxx - sx * sx);
}

// RMS of y about its least-squares line over [t0, t1]: the oscillation left
// about a ramp.
inline double rms_about_line(const Response& r, double t0, double t1) {
  double st = 0.0, sy = 0.0, stt = 0.0, sty = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < r.t.size(); ++i) {
    if (r.t[i] < t0 || r.t[i] > t1) continue;
    st += r.t[i];
    sy += r.y[i];
    stt += r.t[i] * r.t[i];
    sty += r.t[i] * r.y[i];
    ++n;
  }
  if (n < 3) return NAN;
  const double slope = (n * sty - st * sy) / (n * stt - st * st);
  const double icpt = (sy - slope * st) / n;
  double ss = 0.0;
  for (std::size_t i = 0; i < r.t.size(); ++i) {
    if (r.t[i] < t0 || r.t[i] > t1) continue;
    const double d = r.y[i] - (icpt + slope * r.t[i]);
    ss += d * d;
  }
  return std::sqrt(ss / n);
}

}  // namespace rigctl::step_metrics
