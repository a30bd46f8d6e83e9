#include "tools/iterate/iteration_files.hpp"

#include <cstdio>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "tools/common/json_text.hpp"
#include "tools/iterate/rpc3_file.hpp"

namespace rigctl {

namespace {

void write_columns(const std::string& path, const std::string& rig, const std::string& header,
                   const std::vector<const std::vector<double>*>& columns, double period_s) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write " + path);
  f << "# rig: " << rig << "\n# source: rigctl iterate\nt," << header << "\n" << std::setprecision(10);
  const std::size_t n = columns.front()->size();
  for (std::size_t i = 0; i < n; ++i) {
    f << static_cast<double>(i) * period_s;
    for (const auto* c : columns) f << "," << (*c)[i];
    f << "\n";
  }
  if (!f) throw std::runtime_error("write failed: " + path);
}

std::string numbers(const std::vector<double>& v) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + json_number(v[i]);
  return s + "]";
}

double ratio(double measured, double predicted) { return predicted > 0.0 ? measured / predicted : 0.0; }

// Predicted (as the check used it: corrected by the last measured ratio)
// against what the rig did.
std::string prediction_json(const IterationRecord& r) {
  const PredictedMotion& p = r.peaks.predicted;
  std::ostringstream o;
  o << "{\"rod_min\": " << json_number(p.rod_min) << ", \"rod_max\": " << json_number(p.rod_max)
    << ", \"rod_velocity\": " << json_number(p.rod_velocity) << ", \"valve_effort\": " << json_number(p.valve_effort)
    << ", \"correction\": {\"velocity\": " << json_number(r.correction.velocity) << ", \"effort\": "
    << json_number(r.correction.effort) << "}},\n     \"measured\": {\"rod_velocity\": " << json_number(r.measured.rod_velocity)
    << ", \"valve_effort\": " << json_number(r.measured.valve_effort)
    << ", \"rod_velocity_ratio\": " << json_number(ratio(r.measured.rod_velocity, p.rod_velocity))
    << ", \"valve_effort_ratio\": " << json_number(ratio(r.measured.valve_effort, p.valve_effort)) << "}";
  return o.str();
}

std::string iteration_json(const IterationRecord& r, const std::string& dir_hint) {
  std::ostringstream o;
  o << "    {\"iteration\": " << r.index << ", \"rel_rms_percent\": " << json_number(r.match.rel_rms_percent)
    << ", \"whole_rel_rms_percent\": " << json_number(r.match.whole_rel_rms_percent)
    << ", \"trac\": " << json_number(r.match.trac) << ", \"peak_error\": " << json_number(r.match.peak_error)
    << ", \"rms_error\": " << json_number(r.match.rms_error) << ", \"level\": " << json_number(r.level)
    << ", \"growth\": " << json_number(r.growth) << ",\n     \"drive\": {\"min\": " << json_number(r.peaks.min)
    << ", \"max\": " << json_number(r.peaks.max) << ", \"peak_displacement\": " << json_number(r.peaks.displacement)
    << ", \"peak_velocity\": " << json_number(r.peaks.velocity)
    << ", \"scale\": " << json_number(r.drive_scale) << ", \"limited_by\": " << json_string(r.limited_by) << "},\n"
    << "     \"predicted\": " << prediction_json(r) << ",\n     \"gain\": " << numbers(r.gain)
    << ",\n     \"drive_file\": " << json_string(iteration_file(dir_hint, r.index, "drive"))
    << ", \"response_file\": " << json_string(iteration_file(dir_hint, r.index, "response")) << "}";
  return o.str();
}

std::string bands_json(const std::vector<std::pair<double, double>>& bands) {
  std::string s = "[";
  for (std::size_t i = 0; i < bands.size(); ++i) {
    s += (i ? ", [" : "[") + json_number(bands[i].first) + ", " + json_number(bands[i].second) + "]";
  }
  return s + "]";
}

}  // namespace

std::string iteration_file(const std::string& dir, int index, const std::string& kind) {
  char name[64];
  std::snprintf(name, sizeof name, "iter_%02d_%s.csv", index, kind.c_str());
  return dir.empty() ? std::string(name) : dir + "/" + name;
}

void write_drive_file(const std::string& path, const std::string& setpoint, const std::vector<double>& drive,
                      double period_s, const std::string& rig) {
  write_columns(path, rig, setpoint, {&drive}, period_s);
}

void write_response_file(const std::string& path, const std::string& channel, const std::vector<double>& response,
                         const std::vector<double>& target, double period_s, const std::string& rig) {
  write_columns(path, rig, channel + ",target", {&response, &target}, period_s);
}

void write_iteration_rpc3(const std::string& dir, int index, const std::string& setpoint, const std::string& channel,
                          const std::string& unit, const IterationRecord& r, const std::vector<double>& target,
                          double period_s) {
  const std::string base = iteration_file(dir, index, "");
  const std::string stem = base.substr(0, base.size() - 4);  // ".../iter_NN_"
  Rpc3File drive;
  drive.time_type = "DRIVE";
  drive.period_s = period_s;
  drive.channels = {{setpoint, unit, r.drive}};
  write_rpc3_file(drive, stem + "drive.drv");
  Rpc3File response;
  response.time_type = "RESPONSE";
  response.period_s = period_s;
  response.channels = {{channel, unit, r.response}, {"target", unit, target}};
  write_rpc3_file(response, stem + "response.rsp");
}

std::string summary_json(const IterationSummary& s, const IterationOutcome& out) {
  std::ostringstream o;
  const auto& l = s.limits;
  o << "{\n  \"format\": \"rigctl-iterate\",\n  \"version\": 1,\n"
    << "  \"rig\": " << json_string(s.rig) << ",\n  \"config\": " << json_string(s.config)
    << ",\n  \"target\": " << json_string(s.target) << ",\n  \"target_channel\": " << json_string(s.target_channel)
    << ",\n  \"target_period_s\": " << json_number(s.target_period_s) << ",\n  \"target_start_s\": " << json_number(s.target_start_s)
    << ",\n  \"channel\": " << json_string(s.channel)
    << ",\n  \"frf_source\": " << json_string(s.frf_source) << ",\n  \"operating_point\": " << json_number(s.operating_point)
    << ",\n  \"band_hz\": [" << json_number(s.band_min_hz) << ", " << json_number(s.band_max_hz) << "]"
    << ",\n  \"tolerance_percent\": " << json_number(s.tolerance_percent)
    << ",\n  \"lines_gated\": " << s.lines_gated << ",\n  \"bands_gated_hz\": " << bands_json(out.gated_bands_hz)
    << ",\n  \"first_level\": " << json_number(s.first_level) << ",\n  \"max_growth\": " << json_number(s.max_growth)
    << ",\n  \"window_s\": [" << json_number(static_cast<double>(out.window.begin) * s.period_s) << ", "
    << json_number(static_cast<double>(out.window.end) * s.period_s) << "], \"window_source\": " << json_string(out.window.source)
    << ",\n  \"limits\": {\"position\": [" << json_number(l.position_min) << ", " << json_number(l.position_max)
    << "], \"position_source\": " << json_string(l.position_source) << ", \"stroke\": [" << json_number(l.stroke_min)
    << ", " << json_number(l.stroke_max) << "], \"stroke_source\": " << json_string(l.stroke_source)
    << ", \"velocity\": " << json_number(l.velocity_max)
    << ", \"velocity_source\": " << json_string(l.velocity_source) << ", \"valve_effort\": " << json_number(l.effort_max)
    << ", \"valve_effort_source\": " << json_string(l.effort_source) << "}"
    << ",\n  \"end\": " << json_string(std::string(to_string(out.end))) << ",\n  \"end_detail\": " << json_string(out.end_detail)
    << ",\n  \"converged\": " << (out.end == IterationEnd::kTolerance ? "true" : "false")
    << ",\n  \"best_iteration\": " << (out.iterations.empty() ? 0 : out.iterations[out.best].index)
    << ",\n  \"iterations\": [\n";
  for (std::size_t i = 0; i < out.iterations.size(); ++i) o << (i ? ",\n" : "") << iteration_json(out.iterations[i], "");
  o << "\n  ]\n}\n";
  return o.str();
}

void write_text_file(const std::string& path, const std::string& text) {
  std::ofstream f(path);
  f << text;
  if (!f) throw std::runtime_error("cannot write " + path);
}

}  // namespace rigctl
