#include "tools/health/health_report.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "tools/catalog/run_summary.hpp"
#include "tools/common/json_text.hpp"

namespace rigctl::health {

namespace {

std::string utc(double s) { return catalog::utc_text(static_cast<int64_t>(std::llround(s * 1e6))); }

std::string html_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '&') out += "&amp;";
    else out += c;
  }
  return out;
}

void write_alarm_json(const catalog::AlarmEntry& a, std::ostream& out) {
  out << "{\"parameter\": " << json_string(a.parameter) << ", \"stands_for\": " << json_string(a.stands_for)
      << ", \"direction\": " << a.direction << ", \"size_relative\": " << json_number(a.size_relative)
      << ", \"size_sigma\": " << json_number(a.size_sigma) << ", \"since_utc\": " << json_string(utc(a.since_utc_s))
      << ", \"since_utc_s\": " << json_number(a.since_utc_s) << ", \"raised_utc_s\": " << json_number(a.raised_utc_s)
      << ", \"message\": " << json_string(a.message) << "}";
}

// One parameter's plot: the band value +- 2 sigma_used, the values, the
// reference, markers at alarms. Plain SVG, no script.
void write_svg(const ParameterTrend& p, std::ostream& out) {
  constexpr double kW = 760, kH = 220, kL = 70, kR = 10, kT = 10, kB = 30;  // pixels
  if (p.points.empty()) return;
  double t0 = p.points.front().time_utc_s, t1 = p.points.back().time_utc_s;
  if (t1 <= t0) t1 = t0 + 1.0;
  double lo = p.reference, hi = p.reference;
  for (const auto& q : p.points) {
    lo = std::min(lo, q.value - 2 * q.sigma_used);
    hi = std::max(hi, q.value + 2 * q.sigma_used);
  }
  if (hi <= lo) hi = lo + 1.0;
  auto X = [&](double t) { return kL + (kW - kL - kR) * (t - t0) / (t1 - t0); };
  auto Y = [&](double v) { return kT + (kH - kT - kB) * (hi - v) / (hi - lo); };
  out << "<svg width='" << kW << "' height='" << kH << "' xmlns='http://www.w3.org/2000/svg'>\n";
  out << "<polygon fill='#c6dbef' stroke='none' points='";
  for (const auto& q : p.points) out << X(q.time_utc_s) << "," << Y(q.value + 2 * q.sigma_used) << " ";
  for (auto it = p.points.rbegin(); it != p.points.rend(); ++it)
    out << X(it->time_utc_s) << "," << Y(it->value - 2 * it->sigma_used) << " ";
  out << "'/>\n<line x1='" << kL << "' x2='" << kW - kR << "' y1='" << Y(p.reference) << "' y2='" << Y(p.reference)
      << "' stroke='#555' stroke-dasharray='4 3'/>\n<polyline fill='none' stroke='#08519c' points='";
  for (const auto& q : p.points) out << X(q.time_utc_s) << "," << Y(q.value) << " ";
  out << "'/>\n";
  for (const auto& a : p.alarms) {
    out << "<line x1='" << X(a.since_utc_s) << "' x2='" << X(a.since_utc_s) << "' y1='" << kT << "' y2='" << kH - kB
        << "' stroke='#fd8d3c' stroke-dasharray='2 2'/><circle cx='" << X(a.raised_utc_s) << "' cy='" << kT + 6
        << "' r='5' fill='#d62728'/>\n";
  }
  out << "<text x='4' y='" << Y(hi) + 10 << "' font-size='11'>" << std::setprecision(4) << hi << "</text><text x='4' y='"
      << Y(lo) << "' font-size='11'>" << lo << "</text><text x='" << kL << "' y='" << kH - 8 << "' font-size='11'>"
      << utc(t0) << "</text><text x='" << kW - 230 << "' y='" << kH - 8 << "' font-size='11'>" << utc(t1)
      << "</text>\n</svg>\n";
}

}  // namespace

void write_trends_json(const HealthTrends& h, std::ostream& out) {
  out << "{\"rig_name\": " << json_string(h.rig_name) << ", \"diagnoses\": " << h.diagnoses
      << ", \"temperature_measured\": " << (h.temperature_measured ? "true" : "false") << ",\n \"parameters\": [";
  for (std::size_t i = 0; i < h.parameters.size(); ++i) {
    const auto& p = h.parameters[i];
    out << (i ? ",\n" : "\n") << "  {\"name\": " << json_string(p.name) << ", \"unit\": " << json_string(p.unit)
        << ", \"stands_for\": " << json_string(p.stands_for) << ", \"nominal\": " << json_number(p.nominal)
        << ", \"reference\": " << json_number(p.reference) << ", \"reference_scatter\": "
        << json_number(p.reference_scatter) << ", \"undetermined\": " << p.undetermined << ",\n   \"points\": [";
    for (std::size_t j = 0; j < p.points.size(); ++j) {
      const auto& q = p.points[j];
      // A trend no longer than its reference has no chart (null sums).
      const bool charted = j < p.chart.upper.size();
      out << (j ? ", " : "") << "[" << json_number(q.time_utc_s) << ", " << json_number(q.value) << ", "
          << json_number(q.sigma) << ", " << json_number(q.sigma_used) << ", "
          << (charted ? json_number(p.chart.upper[j]) : "null") << ", "
          << (charted ? json_number(p.chart.lower[j]) : "null") << "]";
    }
    out << "],\n   \"alarms\": [";
    for (std::size_t j = 0; j < p.alarms.size(); ++j) {
      out << (j ? ", " : "");
      write_alarm_json(p.alarms[j], out);
    }
    out << "]}";
  }
  out << "\n]}\n";
}

void write_health_html(const HealthTrends& h, std::ostream& out) {
  out << "<!DOCTYPE html><html><head><meta charset='utf-8'><title>rig health: " << html_escape(h.rig_name)
      << "</title><style>body{font-family:sans-serif;max-width:800px;margin:auto}td,th{padding:2px 8px}"
         ".alarm{color:#b00}</style></head><body>\n<h1>Rig health: "
      << html_escape(h.rig_name) << "</h1>\n<p>" << h.diagnoses
      << " diagnosed windows. Each plot: the calibrated parameter (line), &plusmn;2 standard deviations (band: the "
         "fit's, widened by the reference's scatter between windows), the reference (dashed: the mean of the first "
         "windows), alarms (red dot: raised; orange line: since when). docs/rig-health.md says how to read it.</p>\n";
  if (!h.temperature_measured)
    out << "<p><b>Temperature could not be separated:</b> the runs have no T_oil channel, so a change of the bulk "
           "modulus or the leakage may be the oil's temperature rather than wear.</p>\n";
  out << "<h2>Alarms</h2>\n";
  std::size_t n_alarms = 0;
  for (const auto& p : h.parameters)
    for (const auto& a : p.alarms) {
      out << "<p class='alarm'>" << html_escape(a.message) << "</p>\n";
      ++n_alarms;
    }
  if (n_alarms == 0) out << "<p>None.</p>\n";
  for (const auto& p : h.parameters) {
    out << "<h3>" << html_escape(p.name) << " [" << html_escape(p.unit) << "]"
        << (p.stands_for.empty() ? "" : " &mdash; stands for " + html_escape(p.stands_for)) << "</h3>\n<p>"
        << p.points.size() << " windows trended, " << p.undetermined << " could not determine it; reference "
        << std::setprecision(5) << p.reference << " (nominal " << p.nominal << "), scatter beyond the fits "
        << p.reference_scatter << ".</p>\n";
    write_svg(p, out);
  }
  out << "</body></html>\n";
}

}  // namespace rigctl::health
