// Writers of a diagnosis: the JSON of the run-file contract
// (docs/run-files.md 2.3) and the HTML report with inline SVG plots. Apart
// from the engine so that engine.cpp is the method alone.
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "tools/common/json_text.hpp"
#include "tools/diagnosis/engine.hpp"

namespace rigctl::diag {

namespace {

std::string fmt(double v, int prec = 4) {
  std::ostringstream os;
  os << std::setprecision(prec) << v;
  return os.str();
}

}  // namespace

// ---------------------------------------------------------------- JSON

namespace {

// {name: number}
std::string json_number_map(const std::map<std::string, double>& m) {
  std::string s = "{";
  bool first = true;
  for (const auto& [k, v] : m) {
    s += (first ? "" : ", ") + json_string(k) + ": " + json_number(v);
    first = false;
  }
  return s + "}";
}

// {name: value}, null where the run does not determine the value.
std::string json_values(const std::vector<ParamValue>& ps) {
  std::string s = "{";
  for (std::size_t j = 0; j < ps.size(); ++j)
    s += (j ? ", " : "") + json_string(ps[j].name) + ": " + (ps[j].determined ? json_number(ps[j].value) : "null");
  return s + "}";
}

std::string json_names_where(const std::vector<ParamValue>& ps, bool determined) {
  std::string s = "[";
  bool first = true;
  for (const auto& p : ps)
    if (p.determined == determined) {
      s += (first ? "" : ", ") + json_string(p.name);
      first = false;
    }
  return s + "]";
}

std::string json_list(const std::vector<std::string>& v) {
  std::string s = "[";
  for (std::size_t j = 0; j < v.size(); ++j) s += (j ? ", " : "") + json_string(v[j]);
  return s + "]";
}

// The "where" (docs/diagnosis.md 3): the best place with its regressors,
// then every place's shares.
std::string json_where(const WhereResult& w) {
  const auto& b = w.places.front();
  std::string s = "{\"place\": " + json_string(b.name) + ", \"unit\": " + json_string(b.unit) +
                  ", \"significant\": " + (w.significant ? "true" : "false") +
                  ", \"explained_share\": " + json_number(b.explained_share) +
                  ", \"share_above_noise\": " + json_number(b.share_above_noise) + ", \"causes\": " + json_list(b.causes) +
                  ",\n    \"regressors\": [";
  for (std::size_t j = 0; j < b.regressors.size(); ++j)
    s += std::string(j ? ", " : "") + "{\"feature\": " + json_string(b.regressors[j].feature) +
         ", \"coefficient\": " + json_number(b.regressors[j].coefficient) +
         ", \"share\": " + json_number(b.regressors[j].share) + "}";
  s += "],\n    \"sentence\": " + json_string(w.sentence) + ",\n    \"places\": [";
  for (std::size_t j = 0; j < w.places.size(); ++j)
    s += std::string(j ? ",\n      " : "\n      ") + "{\"place\": " + json_string(w.places[j].name) +
         ", \"explained_share\": " + json_number(w.places[j].explained_share) +
         ", \"share_above_noise\": " + json_number(w.places[j].share_above_noise) + "}";
  return s + "]}";
}

// One named cause of the JSON's "causes" list.
void write_cause_json(const CauseResult& c, std::ostream& out) {
  out << "    {\"cause\": " << json_string(c.cause) << ", \"confidence\": " << json_number(c.confidence)
      << ",\n     \"evidence\": " << json_string(c.evidence) << ",\n     \"parameters\": {";
  // A parameter the run cannot determine is null, not its starting value.
  for (std::size_t j = 0; j < c.parameters.size(); ++j)
    out << (j ? ", " : "") << json_string(c.parameters[j].name) << ": "
        << (c.parameters[j].determined ? json_number(c.parameters[j].value) : std::string("null"));
  out << "},\n     \"undetermined_parameters\": " << json_names_where(c.parameters, false);
  out << ",\n     \"parameter_sigma\": {";
  for (std::size_t j = 0; j < c.parameters.size(); ++j)
    out << (j ? ", " : "") << json_string(c.parameters[j].name) << ": "
        << (c.parameters[j].determined ? json_number(c.parameters[j].sigma) : std::string("null"));
  out << "},\n     \"parameter_units\": {";
  for (std::size_t j = 0; j < c.parameters.size(); ++j)
    out << (j ? ", " : "") << json_string(c.parameters[j].name) << ": " << json_string(c.parameters[j].unit);
  out << "},\n     \"baseline_fit_percent\": " << json_number(c.baseline_fit_percent)
      << ", \"extended_fit_percent\": " << json_number(c.extended_fit_percent)
      << ", \"gain_percent_points\": " << json_number(c.gain_percent_points) << ", \"signal\": " << json_string(c.signal)
      << ",\n     \"ambiguous_with\": " << json_list(c.ambiguous_with) << ", \"signature\": " << json_string(c.signature)
      << ", \"where_agrees\": " << (c.where_agrees ? "true" : "false");
  if (!c.channels.empty()) out << ",\n     \"channels\": " << json_list(c.channels);
  if (!c.form.empty())
    out << ",\n     \"form\": " << json_string(c.form) << ", \"form_estimation_cost\": " << json_number_map(c.form_costs);
  out << "}";
}

}  // namespace

void write_json(const Diagnosis& d, std::ostream& out) {
  out << "{\n  \"rig\": " << json_string(d.rig) << ",\n  \"cause\": " << json_string(d.cause) << ",\n  \"causes\": [";
  for (std::size_t i = 0; i < d.causes.size(); ++i) {
    out << (i ? ",\n" : "\n");
    write_cause_json(d.causes[i], out);
  }
  out << (d.causes.empty() ? "],\n" : "\n  ],\n");
  out << "  \"baseline_fit_percent\": " << json_number_map(d.baseline_fit_percent) << ",\n";
  out << "  \"extended_fit_percent\": " << json_number_map(d.extended_fit_percent) << ",\n";
  out << "  \"validation\": " << json_string(d.validation) << ",\n";
  out << "  \"unexplained\": " << (d.unexplained ? "true" : "false") << ",\n";
  if (d.unexplained) {
    const auto& u = d.unexplained_residual;
    out << "  \"unexplained_residual\": {\"signal\": " << json_string(u.signal) << ", \"rms\": " << json_number(u.rms)
        << ", \"noise_floor\": " << json_number(u.noise) << ", \"band_hz\": [" << json_number(u.band_lo_hz) << ", "
        << json_number(u.band_hi_hz) << "], \"peak_hz\": " << json_number(u.peak_hz)
        << ", \"where\": " << json_string(d.where.sentence) << "},\n";
  }
  if (d.where.computed) out << "  \"where\": " << json_where(d.where) << ",\n";
  out << "  \"baseline_calibration\": [";
  for (std::size_t j = 0; j < d.calibration.size(); ++j) {
    const auto& c = d.calibration[j];
    out << (j ? ",\n" : "\n") << "    {\"name\": " << json_string(c.name) << ", \"unit\": " << json_string(c.unit)
        << ", \"nominal\": " << json_number(c.nominal)
        << ", \"value\": " << (c.determined ? json_number(c.value) : std::string("null"))
        << ", \"sigma\": " << (c.determined ? json_number(c.sigma) : std::string("null"))
        << ", \"tolerance\": " << json_number(c.tolerance) << ", \"change_percent\": "
        << (c.determined && c.nominal != 0.0 ? json_number(100.0 * (c.value - c.nominal) / c.nominal) : std::string("null"))
        << ", \"moved\": " << (c.moved ? "true" : "false") << ", \"determined\": " << (c.determined ? "true" : "false");
    if (!c.stands_for.empty())
      out << ", \"stands_for\": " << json_string(c.stands_for)
          << ", \"at_band_edge\": " << (c.at_band_edge ? "true" : "false");
    out << "}";
  }
  out << (d.calibration.empty() ? "],\n" : "\n  ],\n");
  out << "  \"loop_timing\": [";
  bool first_timing = true;
  for (const auto& c : d.calibration) {
    if (!c.timing) continue;
    out << (first_timing ? "\n" : ",\n") << "    {\"name\": " << json_string(c.name) << ", \"unit\": " << json_string(c.unit)
        << ", \"value\": " << (c.determined ? json_number(c.value) : std::string("null"))
        << ", \"sigma\": " << (c.determined ? json_number(c.sigma) : std::string("null")) << ", \"bounds\": ["
        << json_number(c.lo) << ", " << json_number(c.hi) << "]}";
    first_timing = false;
  }
  out << (first_timing ? "],\n" : "\n  ],\n");
  out << "  \"baseline_parameters\": " << json_values(d.baseline_parameters);
  out << ",\n  \"final_parameters\": " << json_values(d.final_parameters);
  out << ",\n  \"undetermined_parameters\": " << json_names_where(d.final_parameters, false);
  out << ",\n  \"model_constants\": " << json_number_map(d.model_constants);
  out << ",\n  \"screened\": [";
  for (std::size_t j = 0; j < d.screened.size(); ++j) {
    const auto& s = d.screened[j];
    out << (j ? ",\n" : "\n") << "    {\"round\": " << s.round << ", \"cause\": " << json_string(s.cause)
        << ", \"estimation_cost\": " << json_number(s.estimation_cost) << ", \"refitted\": " << (s.refitted ? "true" : "false");
    if (s.refitted)
      out << ", \"gain_percent_points\": " << json_number(s.gain_percent_points) << ", \"signal\": " << json_string(s.signal);
    out << ", \"accepted\": " << (s.accepted ? "true" : "false") << ", \"reason\": " << json_string(s.reason) << "}";
  }
  out << (d.screened.empty() ? "],\n" : "\n  ],\n");
  out << "  \"not_implemented_candidates\": [";
  for (std::size_t j = 0; j < d.stubs.size(); ++j) out << (j ? ", " : "") << json_string(d.stubs[j]);
  out << "],\n  \"elapsed_s\": " << json_number(d.elapsed_s) << "\n}\n";
}

// ---------------------------------------------------------------- HTML report

namespace {

struct Series {
  std::string label, color;
  const std::vector<double>* x;
  const std::vector<double>* y;
  bool dots = false;
};

std::string esc(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '<') o += "&lt;";
    else if (c == '>') o += "&gt;";
    else if (c == '&') o += "&amp;";
    else o += c;
  }
  return o;
}

std::string svg_plot(const std::string& title, const std::string& xl, const std::string& yl,
                     const std::vector<Series>& series, double vline = std::numeric_limits<double>::quiet_NaN()) {
  const double W = 900, H = 300, ml = 70, mr = 20, mt = 30, mb = 45;
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  for (const auto& s : series)
    for (std::size_t i = 0; i < std::min(s.x->size(), s.y->size()); ++i) {
      const double x = (*s.x)[i], y = (*s.y)[i];
      if (!std::isfinite(x) || !std::isfinite(y)) continue;
      x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
    }
  if (!(x1 > x0)) x1 = x0 + 1;
  if (!(y1 > y0)) y1 = y0 + 1;
  const double pad = 0.05 * (y1 - y0);
  y0 -= pad, y1 += pad;
  auto X = [&](double x) { return ml + (x - x0) / (x1 - x0) * (W - ml - mr); };
  auto Y = [&](double y) { return H - mb - (y - y0) / (y1 - y0) * (H - mt - mb); };
  std::ostringstream o;
  o << std::setprecision(5);
  o << "<svg xmlns='http://www.w3.org/2000/svg' width='" << W << "' height='" << H << "' viewBox='0 0 " << W << " " << H
    << "' style='background:#fff;border:1px solid #ccc'>\n";
  o << "<text x='" << W / 2 << "' y='18' text-anchor='middle' font-size='14'>" << esc(title) << "</text>\n";
  o << "<rect x='" << ml << "' y='" << mt << "' width='" << W - ml - mr << "' height='" << H - mt - mb
    << "' fill='none' stroke='#888'/>\n";
  for (int k = 0; k <= 4; ++k) {
    const double xv = x0 + (x1 - x0) * k / 4, yv = y0 + (y1 - y0) * k / 4;
    o << "<text x='" << X(xv) << "' y='" << H - mb + 15 << "' text-anchor='middle' font-size='11'>" << std::setprecision(3)
      << xv << "</text>";
    o << "<text x='" << ml - 5 << "' y='" << Y(yv) + 4 << "' text-anchor='end' font-size='11'>" << yv << "</text>\n"
      << std::setprecision(5);
    o << "<line x1='" << ml << "' x2='" << W - mr << "' y1='" << Y(yv) << "' y2='" << Y(yv) << "' stroke='#eee'/>\n";
  }
  o << "<text x='" << W / 2 << "' y='" << H - 8 << "' text-anchor='middle' font-size='12'>" << esc(xl) << "</text>\n";
  o << "<text x='14' y='" << H / 2 << "' text-anchor='middle' font-size='12' transform='rotate(-90 14 " << H / 2 << ")'>"
    << esc(yl) << "</text>\n";
  if (std::isfinite(vline))
    o << "<line x1='" << X(vline) << "' x2='" << X(vline) << "' y1='" << mt << "' y2='" << H - mb
      << "' stroke='#999' stroke-dasharray='4 3'/><text x='" << X(vline) + 4 << "' y='" << mt + 12
      << "' font-size='11' fill='#666'>held out &#8594;</text>\n";
  int li = 0;
  for (const auto& s : series) {
    const std::size_t m = std::min(s.x->size(), s.y->size());
    const std::size_t step = std::max<std::size_t>(1, m / (s.dots ? 3000 : 2500));
    if (s.dots) {
      o << "<g fill='" << s.color << "' fill-opacity='0.35'>";
      for (std::size_t i = 0; i < m; i += step)
        if (std::isfinite((*s.y)[i])) o << "<circle cx='" << X((*s.x)[i]) << "' cy='" << Y((*s.y)[i]) << "' r='1.3'/>";
      o << "</g>\n";
    } else {
      o << "<polyline fill='none' stroke='" << s.color << "' stroke-width='1.2' points='";
      for (std::size_t i = 0; i < m; i += step) o << X((*s.x)[i]) << "," << Y((*s.y)[i]) << " ";
      o << "'/>\n";
    }
    o << "<text x='" << ml + 10 + 200 * li << "' y='" << mt + 14 << "' font-size='12' fill='" << s.color << "'>"
      << esc(s.label) << "</text>\n";
    ++li;
  }
  o << "</svg>\n";
  return o.str();
}

// Where the baseline's misfit is: the places ranked, and the reconstructed
// missing signal at the best one against time and its strongest regressor.
void write_where_html(const Diagnosis& d, std::ostream& out) {
  const auto& w = d.where;
  if (!w.computed) return;
  out << "<h2 id='where'>Where the misfit is</h2>\n<p>Before any candidate: the calibrated baseline misses "
      << esc(w.sentence) << ".</p>\n";
  out << "<table><tr><th>place</th><th>held-out residual explained</th><th>of its part above the noise</th>"
         "<th>regressors (coefficient, share)</th><th>causes entering here</th></tr>\n";
  for (const auto& p : w.places) {
    out << "<tr><td>" << esc(p.name) << " [" << esc(p.unit) << "]</td><td>" << fmt(100.0 * p.explained_share, 3)
        << " %</td><td>" << fmt(100.0 * p.share_above_noise, 3) << " %</td><td>";
    for (const auto& r : p.regressors)
      out << esc(r.feature) << " (" << fmt(r.coefficient, 3) << ", " << fmt(100.0 * r.share, 2) << " %)<br>";
    out << "</td><td>";
    for (const auto& c : p.causes) out << "<code>" << esc(c) << "</code> ";
    out << "</td></tr>\n";
  }
  out << "</table>\n";
  if (w.signal.empty() || w.places.empty()) return;
  const std::string label = "missing signal at " + w.places.front().name + " [" + w.places.front().unit + "]";
  out << svg_plot("Where: " + label, "t [s]", w.places.front().unit, {{label, "#9467bd", &d.t, &w.signal}});
  if (!w.feature_values.empty())
    out << svg_plot("Where: the missing signal against " + w.feature_name, w.feature_name, w.places.front().unit,
                    {{label, "#9467bd", &w.feature_values, &w.signal, true}});
}

}  // namespace

void write_report(const Diagnosis& d, std::ostream& out) {
  out << "<!DOCTYPE html>\n<html><head><meta charset='utf-8'><title>rigctl diagnose: " << esc(d.rig)
      << "</title>\n<style>body{font-family:sans-serif;max-width:960px;margin:1em auto;color:#222}"
         "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:3px 8px;font-size:13px}"
         "code{background:#f4f4f4}</style></head><body>\n";
  out << "<h1>Model-discrepancy diagnosis: " << esc(d.rig) << "</h1>\n";
  out << "<p><b>Cause: <code>" << esc(d.cause) << "</code></b> (" << d.causes.size()
      << " effect(s) found; diagnosis took " << std::setprecision(3) << d.elapsed_s << " s)</p>\n";
  out << "<h2>Effects found</h2><table><tr><th>cause</th><th>signal</th><th>baseline fit %</th><th>extended fit %</th>"
         "<th>gain [pp]</th><th>confidence</th><th>parameters</th></tr>\n";
  for (const auto& c : d.causes) {
    out << "<tr><td>" << esc(c.cause) << "</td><td>" << esc(c.signal) << "</td><td>" << std::setprecision(4)
        << c.baseline_fit_percent << "</td><td>" << c.extended_fit_percent << "</td><td>" << c.gain_percent_points
        << "</td><td>" << c.confidence << "</td><td>";
    for (const auto& p : c.parameters) out << esc(p.name) << " = " << p.value << " &plusmn; " << p.sigma << " " << esc(p.unit) << "<br>";
    out << "</td></tr>\n";
  }
  out << "</table>\n";
  for (const auto& c : d.causes) out << "<p><b>" << esc(c.cause) << "</b>: " << esc(c.evidence) << "</p>\n";
  write_where_html(d, out);
  out << "<h2>Fit per signal (held-out)</h2><table><tr><th>signal</th><th>baseline %</th><th>final %</th></tr>";
  for (const auto& [k, v] : d.baseline_fit_percent)
    out << "<tr><td>" << esc(k) << "</td><td>" << v << "</td><td>" << d.extended_fit_percent.at(k) << "</td></tr>";
  out << "</table><p>" << esc(d.validation) << "</p>\n";
  const double tv = d.validation_start < d.t.size() ? d.t[d.validation_start] : std::numeric_limits<double>::quiet_NaN();
  for (std::size_t o = 0; o < d.output_names.size(); ++o) {
    const auto& nm = d.output_names[o];
    out << "<h3>" << esc(nm) << ": measured vs baseline vs extended</h3>\n";
    out << svg_plot(nm + " (whole record)", "t [s]", nm,
                    {{"measured", "#000", &d.t, &d.measured[o]},
                     {"baseline", "#d62728", &d.t, &d.y_baseline[o]},
                     {"extended", "#1f77b4", &d.t, &d.y_extended[o]}},
                    tv);
    // Zoom on the first 10 % of the held-out part.
    const std::size_t b = d.validation_start, e = std::min(d.t.size(), b + std::max<std::size_t>(50, (d.t.size() - b) / 4));
    static std::vector<std::vector<double>> keep;  // plot buffers (single-threaded report)
    keep.clear();
    auto sl = [&](const std::vector<double>& v) {
      keep.emplace_back(v.begin() + static_cast<std::ptrdiff_t>(b), v.begin() + static_cast<std::ptrdiff_t>(e));
      return &keep.back();
    };
    keep.reserve(4);
    const auto* tx = sl(d.t);
    const auto* m = sl(d.measured[o]);
    const auto* yb = sl(d.y_baseline[o]);
    const auto* ye = sl(d.y_extended[o]);
    out << svg_plot(nm + " (zoom: start of the held-out part)", "t [s]", nm,
                    {{"measured", "#000", tx, m}, {"baseline", "#d62728", tx, yb}, {"extended", "#1f77b4", tx, ye}});
  }
  for (const auto& cp : d.cause_plots) {
    out << "<h3>" << esc(cp.cause) << ": residual of the model before it vs " << esc(cp.indicator_name) << "</h3>\n";
    std::vector<Series> s = {{"residual " + cp.signal + " (measured - model without it)", "#d62728", &cp.indicator, &cp.residual, true}};
    if (!cp.effect_term.empty()) s.push_back({"fitted effect term", "#1f77b4", &cp.indicator, &cp.effect_term, true});
    out << svg_plot(cp.cause + " vs " + cp.indicator_name, cp.indicator_name, "residual / effect", s);
  }
  out << "<h2>Screened candidates</h2><table><tr><th>round</th><th>cause</th><th>estimation SSE (screen)</th>"
         "<th>held-out gain [pp]</th><th>outcome</th></tr>\n";
  for (const auto& s : d.screened)
    out << "<tr><td>" << s.round << "</td><td>" << esc(s.cause) << "</td><td>" << s.estimation_cost << "</td><td>"
        << (s.refitted ? fmt(s.gain_percent_points, 4) + " (" + s.signal + ")" : "-") << "</td><td>"
        << (s.accepted ? "<b>accepted</b>" : esc(s.reason)) << "</td></tr>\n";
  out << "</table>\n";
  if (!d.stubs.empty()) {
    out << "<p>Candidates not implemented yet (never named): ";
    for (const auto& s : d.stubs) out << "<code>" << esc(s) << "</code> ";
    out << "</p>\n";
  }
  out << "</body></html>\n";
}

}  // namespace rigctl::diag
