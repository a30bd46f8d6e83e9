// The run-file columns (docs/run-files.md 1.7) that the telemetry messages of
// one tick carry: one list for every writer of them, the CSV run file
// (tools/runfile/log2csv.cpp) and the JSON messages of the Foxglove server and
// MCAP export (foxglove/telemetry), so a column has one name everywhere.
#pragma once

#include <string>
#include <vector>

#include "rigctl/command_t.hpp"
#include "rigctl/sample_t.hpp"

namespace rigctl {

struct TelemetryColumn {
  std::string name;  // e.g. "x_r"
  std::string unit;  // SI unit, e.g. "m"; "" when the message does not say
};

// The time column; every row and every JSON message has it.
inline constexpr const char* kTimeColumn = "t";

// The command's columns in a run file's order: the setpoint (its unit is the
// feedback input's, which the command message does not carry), then the outputs.
std::vector<TelemetryColumn> command_columns(const rigctl::command_t& command);
// The sample's input channels, in the driver's order.
std::vector<TelemetryColumn> sample_columns(const rigctl::sample_t& sample);

}  // namespace rigctl
