#include "tools/health/trends.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <sstream>

#include "tools/catalog/run_summary.hpp"

namespace rigctl::health {

namespace {

double median(std::vector<double> v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// The reference: the mean of the first points, the rig as it was. The
// scatter between windows that the fits' sigma does not cover (the demand,
// the temperature, what the model lacks): from the second differences of
// the whole trend, x[i+1] - 2 x[i] + x[i-1], robustly (1.4826 x their median
// absolute value / sqrt 6 is the standard deviation of independent Gaussian
// points): a linear drift cancels in them and a step touches only two, so
// the wear being watched does not widen the band it is judged against. The
// chart's sigma is the fit's widened by that scatter: a rig that scatters
// more than its fits say does not alarm on its own scatter.
void set_reference(ParameterTrend& p, std::size_t n_ref) {
  const std::size_t n = std::min(n_ref, p.points.size());
  if (n == 0) return;
  double mean = 0.0;
  for (std::size_t i = 0; i < n; ++i) mean += p.points[i].value;
  p.reference = mean / static_cast<double>(n);
  std::vector<double> second, fit_var;
  for (std::size_t i = 1; i + 1 < p.points.size(); ++i)
    second.push_back(std::abs(p.points[i + 1].value - 2.0 * p.points[i].value + p.points[i - 1].value));
  for (const auto& q : p.points) fit_var.push_back(q.sigma * q.sigma);
  if (!second.empty()) {
    const double total = 1.4826 * median(second) / std::sqrt(6.0);
    p.reference_scatter = std::sqrt(std::max(0.0, total * total - median(fit_var)));
  }
  for (auto& q : p.points) q.sigma_used = std::sqrt(q.sigma * q.sigma + p.reference_scatter * p.reference_scatter);
}

void detect(ParameterTrend& p, const std::string& rig, const TrendSettings& s) {
  std::vector<CusumPoint> pts;
  for (const auto& q : p.points) pts.push_back({q.value, q.sigma_used});
  p.chart = run_cusum(pts, p.reference, s.cusum);
  for (const auto& a : p.chart.alarms) {
    catalog::AlarmEntry e;
    e.rig_name = rig;
    e.parameter = p.name;
    e.stands_for = p.stands_for;
    e.direction = a.direction;
    e.size_relative = p.reference != 0.0 ? a.mean_shift / std::abs(p.reference) : 0.0;
    e.size_sigma = a.mean_shift_sigma;
    e.since_utc_s = p.points[a.since].time_utc_s;
    e.raised_utc_s = p.points[a.raised_at].time_utc_s;
    e.diagnosis_id = p.points[a.raised_at].diagnosis_id;
    e.message = alarm_message(p, e);
    p.alarms.push_back(e);
  }
}

}  // namespace

std::string alarm_message(const ParameterTrend& p, const catalog::AlarmEntry& a) {
  std::ostringstream m;
  m << (p.stands_for.empty() ? "no cause of the list (the baseline's own parameter)" : p.stands_for) << ": " << p.name
    << " " << (a.direction > 0 ? "rose" : "fell") << " " << std::fixed << std::setprecision(1)
    << 100.0 * std::abs(a.size_relative) << " % (" << std::abs(a.size_sigma) << " sd) since "
    << catalog::utc_text(static_cast<int64_t>(std::llround(a.since_utc_s * 1e6)));
  return m.str();
}

HealthTrends build_trends(catalog::Catalog& c, const std::string& rig_name, const TrendSettings& s) {
  HealthTrends h;
  h.rig_name = rig_name;
  std::map<std::string, std::size_t> index;
  const auto diagnoses = c.rig_diagnoses(rig_name);
  h.diagnoses = diagnoses.size();
  for (const auto& d : diagnoses) {
    for (const auto& p : d.parameters) {
      if (p.role != "baseline") continue;
      auto it = index.find(p.name);
      if (it == index.end()) {
        it = index.emplace(p.name, h.parameters.size()).first;
        h.parameters.push_back({p.name, p.unit, p.stands_for, p.nominal.value_or(0.0)});
      }
      auto& trend = h.parameters[it->second];
      if (!p.determined || !p.value || !p.sigma || !(*p.sigma > 0.0)) {
        ++trend.undetermined;
        continue;
      }
      trend.points.push_back({d.time_utc_s, *p.value, *p.sigma, *p.sigma, d.id, d.run_id});
    }
  }
  for (auto& p : h.parameters) {
    set_reference(p, s.reference_points);
    if (p.points.size() > s.reference_points) detect(p, rig_name, s);
  }
  return h;
}

}  // namespace rigctl::health
