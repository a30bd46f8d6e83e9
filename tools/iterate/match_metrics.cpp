#include "tools/iterate/match_metrics.hpp"

#include <cmath>
#include <stdexcept>

#include "tools/iterate/spectrum.hpp"

namespace rigctl {

MatchMetrics match_metrics(const std::vector<double>& target, const std::vector<double>& response, double period_s,
                           double band_min_hz, double band_max_hz, const TestWindow& window) {
  if (target.size() != response.size() || target.empty()) {
    throw std::invalid_argument("match metrics: target and response differ in length");
  }
  if (window.end > target.size() || window.begin >= window.end) throw std::invalid_argument("match metrics: window outside the record");
  const auto t = band_passed(target, period_s, band_min_hz, band_max_hz);
  const auto r = band_passed(response, period_s, band_min_hz, band_max_hz);
  double tt = 0.0, rr = 0.0, tr = 0.0, ee = 0.0, tt_all = 0.0, ee_all = 0.0;
  MatchMetrics m;
  for (std::size_t i = 0; i < t.size(); ++i) {
    const double e = r[i] - t[i];
    tt_all += t[i] * t[i];
    ee_all += e * e;
    if (i < window.begin || i >= window.end) continue;
    tt += t[i] * t[i];
    rr += r[i] * r[i];
    tr += t[i] * r[i];
    ee += e * e;
    m.peak_error = std::max(m.peak_error, std::abs(e));
  }
  if (tt <= 0.0) throw std::invalid_argument("match metrics: the target has no content in the band");
  m.rel_rms_percent = 100.0 * std::sqrt(ee / tt);
  m.whole_rel_rms_percent = 100.0 * std::sqrt(ee_all / tt_all);
  m.trac = rr > 0.0 ? tr * tr / (tt * rr) : 0.0;
  m.rms_error = std::sqrt(ee / static_cast<double>(window.end - window.begin));
  return m;
}

MatchMetrics match_metrics(const std::vector<double>& target, const std::vector<double>& response, double period_s,
                           double band_min_hz, double band_max_hz) {
  return match_metrics(target, response, period_s, band_min_hz, band_max_hz, TestWindow{0, target.size(), "whole record"});
}

}  // namespace rigctl
