// Parameter trends of one rig from its catalog (docs/rig-health.md 4): each
// calibrated baseline parameter over the diagnosed runs and windows, with
// its standard deviation; the windows that could not determine it are
// counted, not trended. The change detector runs on each trend, and its
// alarms name the physical cause the parameter stands for.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "tools/catalog/catalog.hpp"
#include "tools/health/cusum.hpp"

namespace rigctl::health {

struct TrendPoint {
  double time_utc_s = 0.0;
  double value = 0.0, sigma = 0.0;  // sigma: the window's fit
  double sigma_used = 0.0;          // ... widened by the reference's scatter between windows (the chart's)
  int64_t diagnosis_id = 0, run_id = 0;
};

struct ParameterTrend {
  std::string name, unit, stands_for;
  double nominal = 0.0;
  double reference = 0.0;          // mean of the first reference points: the rig as it was
  double reference_scatter = 0.0;  // the spread between windows beyond the fits' own sigma
  std::vector<TrendPoint> points;  // determined windows, oldest first
  int undetermined = 0;            // windows that could not determine it
  CusumTrace chart;
  std::vector<catalog::AlarmEntry> alarms;
};

struct TrendSettings {
  // Points whose mean is the reference, the rig as it was: the first three
  // windows (of a long run: its first minutes; of a series of blocks: its
  // first blocks, during which the wear has already begun). Three: their
  // mean is within 0.6 sd of the rig's; more would take more of a wearing
  // series into its own reference.
  std::size_t reference_points = 3;
  CusumSettings cusum;
};

struct HealthTrends {
  std::string rig_name;
  std::vector<ParameterTrend> parameters;
  std::size_t diagnoses = 0;
  bool temperature_measured = false;  // a T_oil channel in the rig's runs
};

// Reads every diagnosis of the rig, builds each baseline parameter's trend,
// runs the chart and describes its alarms (not yet stored).
HealthTrends build_trends(catalog::Catalog& c, const std::string& rig_name, const TrendSettings& settings);

// The alarm's text: "cross_port_leakage: R_l fell 23 % (6.1 sd) since 2026-11-03T10:00:00Z".
std::string alarm_message(const ParameterTrend& p, const catalog::AlarmEntry& a);

}  // namespace rigctl::health
