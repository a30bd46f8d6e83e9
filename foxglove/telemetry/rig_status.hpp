// The rig's state changes, limit trips and interlocks as Foxglove status
// messages (docs/foxglove.md): read from the STATE channel's messages,
// turned into statuses to set (with an id) and ids to remove when they clear.
#pragma once

#include <set>
#include <string>
#include <vector>

#include "foxglove/server/server.hpp"
#include "rigctl/state_t.hpp"

namespace rigctl::foxglove {

struct StatusChange {
  bool remove = false;  // true: removeStatus for `id`
  std::string id;
  StatusLevel level = StatusLevel::kInfo;
  std::string message;
};

class RigStatus {
 public:
  // The id of the rig-state status (one, replaced on every change).
  static constexpr const char* kStateId = "rig_state";

  std::vector<StatusChange> update(const rigctl::state_t& state);

 private:
  std::string safety_state_;        // "" before the first message
  std::set<std::string> trips_;     // ids of the active trip statuses
};

// True for the events that are a trip of a limit or detector (they raise a status).
bool is_trip_event(const std::string& event);

}  // namespace rigctl::foxglove
