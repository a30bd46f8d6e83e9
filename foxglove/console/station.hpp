// What the console's station panel shows that telemetry does not carry: the
// state machine's command table (which commands each state allows, and why
// the others are refused), the rig's limit detectors with their thresholds
// and actions, and the scope's channels. Sent once, as the serverInfo
// metadata entry kStationMetadataKey (a JSON text), so the page has no copy
// of the table or the config to fall out of step.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace rigctl::foxglove {

inline constexpr const char* kStationMetadataKey = "rigctl.station";

struct StationDetector {
  std::string name;       // the config's key, e.g. "x_r_rate" or "limits.x_r"
  std::string kind;       // "range", "rate", ...
  std::string channel;    // the input (or output) it watches
  std::string threshold;  // e.g. "max 0.6 for 0.01 s"
  std::string action;     // "indicate", "hold", "stop", "interlock"
};

struct StationDescription {
  std::string rig;                          // "quarter_car"
  bool commands = false;                    // the console takes signed commands (operator mode)
  std::string sender_hint;                  // a default sender id for the page
  std::vector<StationDetector> detectors;
  std::vector<std::string> scope_channels;  // the sample's fields to plot by default, in order
  // Each control channel's demand and feedback (x_ref_1 and z_r1, ...), drawn
  // together in one strip per channel; one pair on a one-channel rig.
  std::vector<std::pair<std::string, std::string>> demands;
};

// The JSON text: {"rig", "commands", "senderHint", "detectors": [...],
// "scope": [...], "demands": [[demand, feedback], ...], "states": {STATE: {COMMAND: {"allowed", "to"|"refused"}}}}.
std::string station_json(const StationDescription& station);

}  // namespace rigctl::foxglove
