#include "foxglove/console/station.hpp"

#include <nlohmann/json.hpp>

#include "rt/safety/rig_state_machine.hpp"

namespace rigctl::foxglove {

using nlohmann::json;

namespace {

// transition_rule() for every (state, command): the single table of
// rt/safety, as the page reads it.
json command_table() {
  json states = json::object();
  for (std::size_t s = 0; s < kSafetyStateCount; ++s) {
    const auto from = static_cast<SafetyState>(s);
    json commands = json::object();
    for (std::size_t k = 0; k < kOperatorCommandKindCount; ++k) {
      const auto command = static_cast<OperatorCommandKind>(k);
      const TransitionRule& rule = transition_rule(from, command);
      json r{{"allowed", rule.allowed}};
      if (rule.allowed) {
        r["to"] = std::string(to_string(rule.to));
      } else {
        r["refused"] = std::string(to_string(rule.refused));
      }
      commands[std::string(to_string(command))] = r;
    }
    states[std::string(to_string(from))] = commands;
  }
  return states;
}

}  // namespace

std::string station_json(const StationDescription& station) {
  json detectors = json::array();
  for (const auto& d : station.detectors) {
    detectors.push_back({{"name", d.name},
                         {"kind", d.kind},
                         {"channel", d.channel},
                         {"threshold", d.threshold},
                         {"action", d.action}});
  }
  return json{{"rig", station.rig},
              {"commands", station.commands},
              {"senderHint", station.sender_hint},
              {"detectors", detectors},
              {"scope", station.scope_channels},
              {"demands", station.demands},
              {"states", command_table()}}
      .dump();
}

}  // namespace rigctl::foxglove
