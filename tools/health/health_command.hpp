// `rigctl health analyse` and `rigctl health report` (docs/rig-health.md).
#pragma once

#include <atomic>
#include <ostream>
#include <string>

#include "tools/health/trends.hpp"
#include "tools/health/window_analysis.hpp"

namespace rigctl::health {

struct ReportOptions {
  std::string catalog_path;  // required
  std::string rig_name;      // required
  std::string json_path, html_path, png_path;  // each optional
  TrendSettings trends;
  bool store_alarms = true;  // alarms into the catalog (once each)
};

// Exit codes: 0 done, 2 bad input, 1 other failures.
int run_health_analyse(const AnalyseOptions& options, const std::atomic<bool>& stop, std::ostream& out, std::ostream& err);
int run_health_report(const ReportOptions& options, std::ostream& out, std::ostream& err);

}  // namespace rigctl::health
