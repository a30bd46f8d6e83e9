#include "tools/diagnosis/evidence.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <iomanip>
#include <numbers>
#include <numeric>
#include <sstream>

namespace rigctl::diag {

namespace {

std::string fmt(double v, int prec = 3) {
  std::ostringstream os;
  os << std::setprecision(prec) << v;
  return os.str();
}

// DFT coefficient of x over [b, end) at frequency f (mean removed).
std::complex<double> dft_at(const std::vector<double>& x, double mean, double f, double dt, std::size_t b,
                            std::size_t end) {
  std::complex<double> acc{0.0, 0.0};
  const double w = 2.0 * std::numbers::pi * f * dt;
  for (std::size_t i = b; i < end; ++i) acc += (x[i] - mean) * std::polar(1.0, -w * static_cast<double>(i - b));
  return acc;
}

double mean_of(const std::vector<double>& x, std::size_t b, std::size_t end) {
  double m = 0.0;
  for (std::size_t i = b; i < end; ++i) m += x[i];
  return end > b ? m / static_cast<double>(end - b) : 0.0;
}

// Delay and lag: the phase of the measured channel behind the model's at the
// frequencies where the channel has power, as an equivalent delay. A delay
// keeps it constant; a first-order lag's falls with frequency.
std::string phase_signature(const std::vector<double>& y, const std::vector<double>& ysim, double dt, std::size_t b,
                            std::size_t end) {
  const double length = static_cast<double>(end - b) * dt;
  const double my = mean_of(y, b, end), ms = mean_of(ysim, b, end);
  std::vector<std::pair<double, double>> pts;  // power, frequency
  for (double f = 2.0 / length; f < 0.25 / dt; f *= 1.25) pts.push_back({std::abs(dft_at(y, my, f, dt, b, end)), f});
  std::sort(pts.rbegin(), pts.rend());
  std::vector<double> fs;
  for (std::size_t i = 0; i < std::min<std::size_t>(pts.size(), 4); ++i) fs.push_back(pts[i].second);
  std::sort(fs.begin(), fs.end());
  std::string s = "equivalent delay of the measured channel behind the model";
  for (double f : fs) {
    const auto a = dft_at(y, my, f, dt, b, end), c = dft_at(ysim, ms, f, dt, b, end);
    const double lag = -std::arg(a / c);  // > 0: measured behind
    s += "; " + fmt(f) + " Hz: " + fmt(1e3 * lag / (2.0 * std::numbers::pi * f)) + " ms";
  }
  return s + " (a delay holds it constant over frequency, a lag lets it fall)";
}

}  // namespace

double binned_r2(const std::vector<double>& ind, const std::vector<double>& e, std::size_t b, std::size_t end) {
  if (ind.size() < end || end <= b + 20) return 0.0;
  std::vector<std::size_t> idx(end - b);
  std::iota(idx.begin(), idx.end(), b);
  std::sort(idx.begin(), idx.end(), [&](auto i, auto j) { return ind[i] < ind[j]; });
  const std::size_t bins = 20, n = idx.size();
  double mean = 0.0;
  for (auto i : idx) mean += e[i];
  mean /= static_cast<double>(n);
  double tot = 0.0, expl = 0.0;
  for (auto i : idx) tot += (e[i] - mean) * (e[i] - mean);
  for (std::size_t k = 0; k < bins; ++k) {
    const std::size_t lo = k * n / bins, hi = (k + 1) * n / bins;
    if (hi <= lo) continue;
    double m = 0.0;
    for (std::size_t j = lo; j < hi; ++j) m += e[idx[j]];
    m /= static_cast<double>(hi - lo);
    expl += static_cast<double>(hi - lo) * (m - mean) * (m - mean);
  }
  return tot > 0.0 ? expl / tot : 0.0;
}

std::string signature(const std::string& cause, const std::string& ind_name, const std::vector<double>& ind,
                      const std::vector<double>& e, const std::vector<double>& y, const std::vector<double>& ysim,
                      double dt, std::size_t b, std::size_t end) {
  if (cause == "sensor_delay" || cause == "actuator_lag" || cause == "command_lag")
    return phase_signature(y, ysim, dt, b, end);
  if (ind.size() < end || end <= b + 20) return {};
  // Mean residual by the sign of the indicator, and (for reversal-indexed
  // causes) in the first and the last third of the travel since a reversal.
  double pos = 0.0, neg = 0.0, amax = 0.0;
  std::size_t np = 0, nn = 0;
  for (std::size_t i = b; i < end; ++i) {
    amax = std::max(amax, std::abs(ind[i]));
    if (ind[i] > 0.0) pos += e[i], ++np;
    if (ind[i] < 0.0) neg += e[i], ++nn;
  }
  pos = np ? pos / static_cast<double>(np) : 0.0;
  neg = nn ? neg / static_cast<double>(nn) : 0.0;
  std::string s = "residual by the sign of " + ind_name + ": mean " + fmt(pos) + " (positive) vs " + fmt(neg) +
                  " (negative)";
  if (cause == "bladder_hysteresis" || cause == "coulomb_friction" || cause == "hysteresis") {
    // Step (Coulomb): the signed residual is already at its level just after
    // a reversal; ramp (hysteresis): it grows with the travel.
    double near = 0.0, far = 0.0;
    std::size_t nn2 = 0, nf = 0;
    for (std::size_t i = b; i < end; ++i) {
      const double a = std::abs(ind[i]), sg = ind[i] > 0 ? 1.0 : -1.0;
      if (a > 0.0 && a < amax / 6.0) near += sg * e[i], ++nn2;
      if (a > amax / 2.0) far += sg * e[i], ++nf;
    }
    near = nn2 ? near / static_cast<double>(nn2) : 0.0;
    far = nf ? far / static_cast<double>(nf) : 0.0;
    s += "; signed residual just after a reversal " + fmt(near) + ", late in the stroke " + fmt(far) +
         (std::abs(near) < 0.6 * std::abs(far) ? " (ramps with the travel: a loop)" : " (at once: a step)");
  }
  return s;
}

double noise_floor(const std::vector<double>& y) {
  if (y.size() < 4) return 0.0;
  double s2 = 0.0, q = 0.0;
  std::vector<double> steps;
  for (std::size_t i = 1; i + 1 < y.size(); ++i) {
    const double d2 = y[i + 1] - 2.0 * y[i] + y[i - 1];
    s2 += d2 * d2;
    const double d = std::abs(y[i] - y[i - 1]);
    if (d > 0.0) steps.push_back(d);
  }
  // White noise of sd s has second differences of variance 6 s^2.
  const double white = std::sqrt(s2 / static_cast<double>(y.size() - 2) / 6.0);
  if (!steps.empty()) {
    std::nth_element(steps.begin(), steps.begin(), steps.end());
    q = *std::min_element(steps.begin(), steps.end()) / std::sqrt(12.0);
  }
  return std::max(white, q);
}

Band power_band(const std::vector<double>& e, double dt, std::size_t b, std::size_t end) {
  Band band;
  if (end <= b + 8) return band;
  const double length = static_cast<double>(end - b) * dt, m = mean_of(e, b, end);
  std::vector<double> f, p;
  for (double x = 1.0 / length; x < 0.5 / dt; x *= 1.15) {
    f.push_back(x);
    // Each log bin stands for a band of width 0.15 x: weight by it.
    p.push_back(std::norm(dft_at(e, m, x, dt, b, end)) * x);
  }
  const double total = std::accumulate(p.begin(), p.end(), 0.0);
  if (!(total > 0.0)) return band;
  double acc = 0.0;
  for (std::size_t i = 0; i < f.size(); ++i) {
    const double before = acc;
    acc += p[i];
    if (before < 0.1 * total && acc >= 0.1 * total) band.lo_hz = f[i];
    if (before < 0.9 * total && acc >= 0.9 * total) band.hi_hz = f[i];
  }
  band.peak_hz = f[static_cast<std::size_t>(std::max_element(p.begin(), p.end()) - p.begin())];
  return band;
}

}  // namespace rigctl::diag
