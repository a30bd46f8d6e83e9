#include "tools/suspension/suspension_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <numbers>
#include <stdexcept>

namespace rigctl {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// ISO 2631-1:1997 Table A.1, Wk.
constexpr double kF1 = 0.4, kQ1 = 0.70710678118654752;
constexpr double kF2 = 100.0, kQ2 = 0.70710678118654752;
constexpr double kF3 = 12.5, kF4 = 12.5, kQ4 = 0.63;
constexpr double kF5 = 2.37, kQ5 = 0.91, kF6 = 3.35, kQ6 = 0.91;

std::span<const double> view(const std::vector<double>& v) { return {v.data(), v.size()}; }

}  // namespace

double peak_abs(std::span<const double> x) {
  double p = 0.0;
  for (double v : x) p = std::max(p, std::abs(v));
  return p;
}

double rms(std::span<const double> x) {
  if (x.empty()) return 0.0;
  double s = 0.0;
  for (double v : x) s += v * v;
  return std::sqrt(s / static_cast<double>(x.size()));
}

double iso2631_wk_gain(double f_hz) {
  using C = std::complex<double>;
  const C s(0.0, kTwoPi * f_hz);
  const double w1 = kTwoPi * kF1, w2 = kTwoPi * kF2, w3 = kTwoPi * kF3, w4 = kTwoPi * kF4;
  const double w5 = kTwoPi * kF5, w6 = kTwoPi * kF6;
  const C hh = s * s / (s * s + s * w1 / kQ1 + w1 * w1);
  const C hl = w2 * w2 / (s * s + s * w2 / kQ2 + w2 * w2);
  const C ht = (1.0 + s / w3) / (1.0 + s / (kQ4 * w4) + s * s / (w4 * w4));
  const C hs = (s * s + s * w5 / kQ5 + w5 * w5) / (s * s + s * w6 / kQ6 + w6 * w6);
  return std::abs(hh * hl * ht * hs);
}

IsoWkFilter::IsoWkFilter(double sample_rate_hz) : fs_(sample_rate_hz) {
  if (!(sample_rate_hz > 0.0)) throw std::invalid_argument("Wk filter: sample rate must be positive");
  const double w1 = kTwoPi * kF1, w2 = kTwoPi * kF2, w3 = kTwoPi * kF3, w4 = kTwoPi * kF4;
  const double w5 = kTwoPi * kF5, w6 = kTwoPi * kF6;
  add(1.0, 0.0, 0.0, 1.0, w1 / kQ1, w1 * w1, 0.0);                          // high-pass band limit
  if (kF2 < 0.45 * fs_) add(0.0, 0.0, w2 * w2, 1.0, w2 / kQ2, w2 * w2, kF2);  // low-pass band limit
  add(0.0, 1.0 / w3, 1.0, 1.0 / (w4 * w4), 1.0 / (kQ4 * w4), 1.0, kF4);      // a-v transition
  add(1.0, w5 / kQ5, w5 * w5, 1.0, w6 / kQ6, w6 * w6, 0.0);                   // upward step
}

// Section (b_s2 s^2 + b_s1 s + b_s0) / (a_s2 s^2 + a_s1 s + a_s0) by the
// bilinear transform s = k (1 - z^-1) / (1 + z^-1), k = 2 fs, or prewarped
// to keep the gain exact at warp_hz.
void IsoWkFilter::add(double b_s2, double b_s1, double b_s0, double a_s2, double a_s1, double a_s0, double warp_hz) {
  double k = 2.0 * fs_;
  if (warp_hz > 0.0) k = kTwoPi * warp_hz / std::tan(std::numbers::pi * warp_hz / fs_);
  const double k2 = k * k;
  const double n0 = b_s2 * k2 + b_s1 * k + b_s0, n1 = 2.0 * (b_s0 - b_s2 * k2), n2 = b_s2 * k2 - b_s1 * k + b_s0;
  const double d0 = a_s2 * k2 + a_s1 * k + a_s0, d1 = 2.0 * (a_s0 - a_s2 * k2), d2 = a_s2 * k2 - a_s1 * k + a_s0;
  Biquad& q = sections_[count_++];
  q.b0 = n0 / d0;
  q.b1 = n1 / d0;
  q.b2 = n2 / d0;
  q.a1 = d1 / d0;
  q.a2 = d2 / d0;
}

void IsoWkFilter::reset() noexcept {
  for (auto& q : sections_) q.s1 = q.s2 = 0.0;
}

double IsoWkFilter::step(double x) noexcept {
  for (std::size_t i = 0; i < count_; ++i) {
    Biquad& q = sections_[i];
    const double y = q.b0 * x + q.s1;
    q.s1 = q.b1 * x - q.a1 * y + q.s2;
    q.s2 = q.b2 * x - q.a2 * y;
    x = y;
  }
  return x;
}

double IsoWkFilter::gain(double f_hz) const {
  const std::complex<double> z1 = std::polar(1.0, -kTwoPi * f_hz / fs_);  // z^-1
  std::complex<double> h(1.0, 0.0);
  for (std::size_t i = 0; i < count_; ++i) {
    const Biquad& q = sections_[i];
    h *= (q.b0 + q.b1 * z1 + q.b2 * z1 * z1) / (1.0 + q.a1 * z1 + q.a2 * z1 * z1);
  }
  return std::abs(h);
}

double wk_weighted_rms(std::span<const double> acceleration, double dt) {
  if (acceleration.empty()) return 0.0;
  IsoWkFilter filter(1.0 / dt);
  double s = 0.0;
  for (double a : acceleration) {
    const double y = filter.step(a);
    s += y * y;
  }
  return std::sqrt(s / static_cast<double>(acceleration.size()));
}

SuspensionMetrics compute_suspension_metrics(const SuspensionRun& run, const SettlingSpec& settling) {
  if (!(run.dt > 0.0)) throw std::invalid_argument("metrics: dt must be positive");
  SuspensionMetrics m;
  m.peak_z_s = peak_abs(view(run.z_s));
  m.rms_z_s = rms(view(run.z_s));
  m.peak_acc = peak_abs(view(run.z_s_ddot));
  m.rms_acc = rms(view(run.z_s_ddot));
  m.wk_rms_acc = wk_weighted_rms(view(run.z_s_ddot), run.dt);

  // Settling.
  double peak_dev = 0.0;
  for (double z : run.z_s) peak_dev = std::max(peak_dev, std::abs(z - settling.settle_value));
  const double band = std::max(settling.fraction * peak_dev, settling.min_band);
  const auto start = static_cast<std::size_t>(std::max(0.0, std::round(run.disturbance_start / run.dt)));
  std::size_t last_out = run.z_s.size();  // none
  for (std::size_t i = start; i < run.z_s.size(); ++i) {
    if (std::abs(run.z_s[i] - settling.settle_value) > band) last_out = i;
  }
  if (last_out == run.z_s.size()) {
    m.settling_time = 0.0;
  } else {
    m.settled = last_out + 1 < run.z_s.size();
    m.settling_time = static_cast<double>(last_out + 1 - start) * run.dt;
  }

  // Jerk.
  double jerk_peak = 0.0, jerk_sq = 0.0;
  for (std::size_t i = 1; i < run.z_s_ddot.size(); ++i) {
    const double j = (run.z_s_ddot[i] - run.z_s_ddot[i - 1]) / run.dt;
    jerk_peak = std::max(jerk_peak, std::abs(j));
    jerk_sq += j * j;
  }
  m.peak_jerk = jerk_peak;
  m.rms_jerk = run.z_s_ddot.size() > 1 ? std::sqrt(jerk_sq / static_cast<double>(run.z_s_ddot.size() - 1)) : 0.0;

  for (std::size_t i = 0; i < 2; ++i) {
    m.peak_travel[i] = peak_abs(view(run.travel[i]));
    m.peak_tyre_deflection[i] = peak_abs(view(run.tyre_deflection[i]));
    m.peak_force[i] = peak_abs(view(run.force[i]));
    double lost = 0.0;
    for (double c : run.contact[i]) lost += c < 0.5 ? run.dt : 0.0;
    m.time_without_contact[i] = lost;
  }
  m.peak_phi = peak_abs(view(run.phi));
  m.peak_phi_ddot = peak_abs(view(run.phi_ddot));
  m.rms_phi_ddot = rms(view(run.phi_ddot));
  return m;
}

double reduction_percent(double passive, double active) {
  if (passive == 0.0) return 0.0;
  return 100.0 * (1.0 - active / passive);
}

std::string format_metrics_table(const std::vector<std::string>& names, const std::vector<SuspensionMetrics>& runs) {
  std::string out;
  char buf[160];
  std::snprintf(buf, sizeof buf, "%-28s", "metric");
  out += buf;
  for (const auto& n : names) {
    std::snprintf(buf, sizeof buf, "%14s", n.c_str());
    out += buf;
  }
  out += "\n";
  auto row = [&](const char* label, double scale, auto get) {
    std::snprintf(buf, sizeof buf, "%-28s", label);
    out += buf;
    for (const auto& r : runs) {
      std::snprintf(buf, sizeof buf, "%14.4f", scale * get(r));
      out += buf;
    }
    out += "\n";
  };
  using M = SuspensionMetrics;
  row("peak z_s [mm]", 1e3, [](const M& m) { return m.peak_z_s; });
  row("rms z_s [mm]", 1e3, [](const M& m) { return m.rms_z_s; });
  row("peak z_s'' [m/s^2]", 1.0, [](const M& m) { return m.peak_acc; });
  row("rms z_s'' [m/s^2]", 1.0, [](const M& m) { return m.rms_acc; });
  row("Wk rms z_s'' [m/s^2]", 1.0, [](const M& m) { return m.wk_rms_acc; });
  row("settling time [s]", 1.0, [](const M& m) { return m.settling_time; });
  row("peak jerk [m/s^3]", 1.0, [](const M& m) { return m.peak_jerk; });
  row("rms jerk [m/s^3]", 1.0, [](const M& m) { return m.rms_jerk; });
  row("peak travel 1 [mm]", 1e3, [](const M& m) { return m.peak_travel[0]; });
  row("peak travel 2 [mm]", 1e3, [](const M& m) { return m.peak_travel[1]; });
  row("peak tyre defl 1 [mm]", 1e3, [](const M& m) { return m.peak_tyre_deflection[0]; });
  row("peak tyre defl 2 [mm]", 1e3, [](const M& m) { return m.peak_tyre_deflection[1]; });
  row("peak force 1 [N]", 1.0, [](const M& m) { return m.peak_force[0]; });
  row("peak force 2 [N]", 1.0, [](const M& m) { return m.peak_force[1]; });
  row("time lifted 1 [s]", 1.0, [](const M& m) { return m.time_without_contact[0]; });
  row("time lifted 2 [s]", 1.0, [](const M& m) { return m.time_without_contact[1]; });
  row("peak phi [mrad]", 1e3, [](const M& m) { return m.peak_phi; });
  row("peak phi'' [rad/s^2]", 1.0, [](const M& m) { return m.peak_phi_ddot; });
  row("rms phi'' [rad/s^2]", 1.0, [](const M& m) { return m.rms_phi_ddot; });
  return out;
}

}  // namespace rigctl
