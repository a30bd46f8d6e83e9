// Ride and handling metrics of a recorded half-car run (seed 001's
// comparisons), computed after the run from sample vectors: not real-time.
//
// Definitions:
//  * peak = max |x|, RMS = sqrt(mean x^2) over the whole record.
//  * Frequency-weighted RMS of the body acceleration: ISO 2631-1:1997
//    weighting Wk (vertical, whole body), the product of the standard's
//    Annex A transfer functions (band limiting high-pass f1 = 0.4 Hz and
//    low-pass f2 = 100 Hz, both Q = 1/sqrt(2); acceleration-velocity
//    transition f3 = f4 = 12.5 Hz, Q4 = 0.63; upward step f5 = 2.37 Hz,
//    Q5 = 0.91, f6 = 3.35 Hz, Q6 = 0.91, written
//    (s^2 + s w5/Q5 + w5^2) / (s^2 + s w6/Q6 + w6^2): gain (f5/f6)^2 = 0.50
//    below the step and 1 above it, as the standard's table requires (0.482
//    at 1 Hz, 1.054 at 6.3 Hz)), discretised section by section with the
//    bilinear transform (the transition and the 100 Hz low-pass prewarped
//    to their corners; the low-pass dropped when 100 Hz is at or above 0.45
//    of the sample rate, where the record holds nothing it would weight).
//    The analog weighting matches the standard's table within 0.3 % from
//    0.1 to 80 Hz; at 400 Hz sampling the discrete one is within 0.5 % up to
//    20 Hz and falls below it above (-2 % at 40 Hz, -5 % at 63 Hz, -9 % at
//    80 Hz): the bilinear map squeezes the band towards Nyquist. RMS over
//    the whole record.
//  * Settling time: with band = max(fraction * peak |z_s - settle_value|,
//    min_band), the time from disturbance_start until z_s enters the band
//    for the last time (the sample after the last one outside it). If the
//    record ends outside the band, `settled` is false and the time runs to
//    the end of the record.
//  * Jerk: first difference of the body acceleration over dt; peak and RMS.
//  * Per corner: peak |suspension travel|, peak |tyre deflection| (change of
//    the tyre's compression from static, z_r - z_u), peak |actuator force|,
//    time without tyre contact.
//  * Angle: peak |phi|, peak and RMS |phi''|.
#pragma once

#include <array>
#include <span>
#include <string>
#include <vector>

namespace rigctl {

struct SuspensionRun {
  double dt = 0.0025;               // [s] sample interval
  double disturbance_start = 0.0;   // [s] after the first sample: settling is timed from here
  std::vector<double> z_s;          // body heave [m]
  std::vector<double> z_s_ddot;     // body heave acceleration [m/s^2]
  std::vector<double> phi;          // body angle [rad]
  std::vector<double> phi_ddot;     // [rad/s^2]
  std::array<std::vector<double>, 2> travel;           // suspension travel per corner [m]
  std::array<std::vector<double>, 2> tyre_deflection;  // z_r - z_u per corner [m]
  std::array<std::vector<double>, 2> force;            // actuator force per corner [N] (may be empty)
  std::array<std::vector<double>, 2> contact;          // 1 in contact, 0 lifted (may be empty)
};

struct SettlingSpec {
  double fraction = 0.05;     // of the peak deviation
  double min_band = 0.0;      // [m] floor of the band (e.g. sensor noise)
  double settle_value = 0.0;  // [m] where z_s settles (0 for a regulator after a bump)
};

struct SuspensionMetrics {
  double peak_z_s = 0.0, rms_z_s = 0.0;          // [m]
  double peak_acc = 0.0, rms_acc = 0.0;          // [m/s^2]
  double wk_rms_acc = 0.0;                       // [m/s^2] ISO 2631-1 Wk weighted
  double settling_time = 0.0;                    // [s]
  bool settled = true;
  double peak_jerk = 0.0, rms_jerk = 0.0;        // [m/s^3]
  std::array<double, 2> peak_travel{};           // [m]
  std::array<double, 2> peak_tyre_deflection{};  // [m]
  std::array<double, 2> peak_force{};            // [N]
  std::array<double, 2> time_without_contact{};  // [s]
  double peak_phi = 0.0;                         // [rad]
  double peak_phi_ddot = 0.0, rms_phi_ddot = 0.0;  // [rad/s^2]
};

SuspensionMetrics compute_suspension_metrics(const SuspensionRun& run, const SettlingSpec& settling = {});

// 100 (1 - active / passive): positive when active is smaller.
double reduction_percent(double passive, double active);

// One line per metric, columns per run, for printing comparisons.
std::string format_metrics_table(const std::vector<std::string>& names, const std::vector<SuspensionMetrics>& runs);

double peak_abs(std::span<const double> x);
double rms(std::span<const double> x);

// ISO 2631-1 Wk: |H(j 2 pi f)| of the analog weighting (Annex A).
double iso2631_wk_gain(double f_hz);

// The discretised Wk weighting: a cascade of bilinear-transformed sections.
class IsoWkFilter {
 public:
  explicit IsoWkFilter(double sample_rate_hz);
  void reset() noexcept;
  double step(double x) noexcept;
  // |H(e^{j 2 pi f / fs})| of the discrete cascade.
  double gain(double f_hz) const;

 private:
  struct Biquad {
    double b0 = 1, b1 = 0, b2 = 0, a1 = 0, a2 = 0;
    double s1 = 0, s2 = 0;  // transposed direct form II state
  };
  void add(double b_s2, double b_s1, double b_s0, double a_s2, double a_s1, double a_s0, double warp_hz);
  double fs_;
  std::array<Biquad, 4> sections_{};
  std::size_t count_ = 0;
};

// RMS of the Wk-weighted signal (filter started at rest).
double wk_weighted_rms(std::span<const double> acceleration, double dt);

}  // namespace rigctl
