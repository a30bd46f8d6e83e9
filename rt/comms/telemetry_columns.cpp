#include "rt/comms/telemetry_columns.hpp"

#include <algorithm>

namespace rigctl {

namespace {

std::vector<TelemetryColumn> named(const std::vector<std::string>& names, const std::vector<std::string>& units) {
  std::vector<TelemetryColumn> out;
  out.reserve(names.size());
  for (std::size_t i = 0; i < names.size(); ++i) out.push_back({names[i], i < units.size() ? units[i] : ""});
  return out;
}

}  // namespace

std::vector<TelemetryColumn> command_columns(const rigctl::command_t& command) {
  std::vector<TelemetryColumn> out{{command.setpoint_name, ""}};
  const auto outputs = named(command.names, command.units);
  out.insert(out.end(), outputs.begin(), outputs.end());
  return out;
}

std::vector<TelemetryColumn> sample_columns(const rigctl::sample_t& sample) { return named(sample.names, sample.units); }

}  // namespace rigctl
