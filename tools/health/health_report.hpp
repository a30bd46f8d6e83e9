// The health report of one rig (`rigctl health report`): the trends as JSON
// (read by tools/plots/plot_health.py for the PNG) and a self-contained HTML
// page with inline SVG plots: each parameter with its uncertainty band, the
// reference, the CUSUM sums and the alarms (docs/rig-health.md 4).
#pragma once

#include <ostream>

#include "tools/health/trends.hpp"

namespace rigctl::health {

void write_trends_json(const HealthTrends& h, std::ostream& out);
void write_health_html(const HealthTrends& h, std::ostream& out);

}  // namespace rigctl::health
