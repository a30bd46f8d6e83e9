#include "rt/control/setpoint_profile.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace rigctl {

double LeadIn::duration() const noexcept { return hold_s + std::abs(target - start) / rate; }

void LeadIn::rebase(double position) noexcept {
  const double ramp_time = std::abs(target - start) / rate;
  start = position;
  const double distance = std::abs(target - start);
  // A configured lead-in without a ramp keeps none: then any move is at the
  // configured rate (the hold then simply lasts a little longer overall).
  if (ramp_time > 0.0 && distance > 0.0) rate = distance / ramp_time;
}

double LeadIn::at(double t) const noexcept {
  if (t <= hold_s) return start;
  const double travelled = (t - hold_s) * rate;
  const double distance = std::abs(target - start);
  if (travelled >= distance) return target;
  return start + std::copysign(travelled, target - start);
}

RampStepsProfile::RampStepsProfile(LeadIn lead_in, std::vector<double> steps, double step_hold_s)
    : lead_in_(lead_in), steps_(std::move(steps)), step_hold_s_(step_hold_s) {}

double RampStepsProfile::step_time(std::size_t i) const noexcept {
  return lead_in_.duration() + static_cast<double>(i) * step_hold_s_;
}

double RampStepsProfile::at(double t) const noexcept {
  const double t_steps = t - lead_in_.duration();
  if (t_steps < 0.0 || steps_.empty()) return lead_in_.at(t);
  const auto i = std::min(static_cast<std::size_t>(t_steps / step_hold_s_), steps_.size() - 1);
  return lead_in_.target + steps_[i];
}

double RampStepsProfile::duration() const noexcept { return step_time(steps_.size()); }

SineProfile::SineProfile(LeadIn lead_in, double amplitude, double frequency_hz, double cycles)
    : lead_in_(lead_in), amplitude_(amplitude), frequency_hz_(frequency_hz), cycles_(cycles) {}

double SineProfile::at(double t) const noexcept {
  const double ts = t - lead_in_.duration();
  if (ts < 0.0) return lead_in_.at(t);
  if (ts > cycles_ / frequency_hz_) return lead_in_.target;
  return lead_in_.target + amplitude_ * std::sin(2.0 * std::numbers::pi * frequency_hz_ * ts);
}

double SineProfile::duration() const noexcept { return lead_in_.duration() + cycles_ / frequency_hz_; }

TableProfile::TableProfile(std::vector<double> t, std::vector<double> value) : t_(std::move(t)), value_(std::move(value)) {
  if (t_.size() < 2 || t_.size() != value_.size()) throw std::invalid_argument("profile table needs at least two rows");
  for (std::size_t i = 1; i < t_.size(); ++i) {
    if (!(t_[i] > t_[i - 1])) throw std::invalid_argument("profile table time must increase strictly");
  }
}

namespace {
std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) {
    const auto b = cell.find_first_not_of(" \t\r");
    const auto e = cell.find_last_not_of(" \t\r");
    cells.push_back(b == std::string::npos ? "" : cell.substr(b, e - b + 1));
  }
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}

double parse_cell(const std::string& cell, const std::string& where) {
  std::size_t used = 0;
  double v = 0.0;
  try {
    v = std::stod(cell, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != cell.size() || !std::isfinite(v)) {
    throw std::runtime_error(where + ": '" + cell + "' is not a finite number");
  }
  return v;
}
}  // namespace

TableProfile TableProfile::from_csv(const std::string& path, const std::string& column) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open profile file");
  std::string line;
  int line_no = 0;
  int t_col = -1, v_col = -1;
  std::vector<double> t, v;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line == "\r" || line[0] == '#') continue;
    const auto cells = split_csv_line(line);
    if (t_col < 0) {
      for (std::size_t i = 0; i < cells.size(); ++i) {
        if (cells[i] == "t") t_col = static_cast<int>(i);
        if (cells[i] == column) v_col = static_cast<int>(i);
      }
      if (t_col < 0) throw std::runtime_error(path + ": header has no column 't'");
      if (v_col < 0) throw std::runtime_error(path + ": header has no column '" + column + "'");
      continue;
    }
    const auto need = static_cast<std::size_t>(std::max(t_col, v_col));
    if (cells.size() <= need) throw std::runtime_error(path + ":" + std::to_string(line_no) + ": short row");
    const std::string where = path + ":" + std::to_string(line_no);
    t.push_back(parse_cell(cells[static_cast<std::size_t>(t_col)], where + " column t"));
    v.push_back(parse_cell(cells[static_cast<std::size_t>(v_col)], where + " column " + column));
    if (t.size() > 1 && !(t.back() > t[t.size() - 2])) {
      throw std::runtime_error(where + ": time does not increase");
    }
  }
  if (t.size() < 2) throw std::runtime_error(path + ": profile needs at least two data rows");
  return TableProfile(std::move(t), std::move(v));
}

double TableProfile::at(double t) const noexcept {
  if (t <= t_.front()) return value_.front();
  if (t >= t_.back()) return value_.back();
  const auto it = std::upper_bound(t_.begin(), t_.end(), t);
  const auto i = static_cast<std::size_t>(it - t_.begin());
  const double w = (t - t_[i - 1]) / (t_[i] - t_[i - 1]);
  return value_[i - 1] + w * (value_[i] - value_[i - 1]);
}

FilteredProfile::FilteredProfile(std::unique_ptr<SetpointProfile> raw, double tau_s, double period_s)
    : raw_(std::move(raw)), alpha_(tau_s > 0.0 ? 1.0 - std::exp(-period_s / tau_s) : 1.0) {}

double FilteredProfile::next(double t) noexcept {
  const double x = raw_->at(t);
  if (!primed_) {
    y_ = x;
    primed_ = true;
  } else {
    y_ += alpha_ * (x - y_);
  }
  return y_;
}

}  // namespace rigctl
