#include "foxglove/telemetry/rig_status.hpp"

#include <algorithm>
#include <array>
#include <string_view>

namespace rigctl::foxglove {

namespace {

// The events of rt/telemetry_record.hpp that a detector raises when a limit
// is crossed or an input fails (SAFETY.md): each is a status until it clears.
constexpr std::array<std::string_view, 12> kTripEvents = {
    "limit_tripped", "input_invalid", "driver_read_failed", "rate_limit",  "tracking_error", "valve_saturated",
    "sample_stale",  "overruns",      "open_circuit",       "sensor_stuck", "stop_timeout",  "log_write_failed"};

StatusLevel level_of_state(const std::string& safety_state) {
  if (safety_state == "faulted") return StatusLevel::kError;
  if (safety_state == "holding" || safety_state == "stopping") return StatusLevel::kWarning;
  return StatusLevel::kInfo;
}

// The channel a trip names: its message starts with it ("x_r = 0.18 m outside
// its limits"), so one status per detector and channel, replaced when the
// same one trips again.
std::string trip_id(const rigctl::state_t& st) {
  const auto end = st.message.find_first_of(" :");
  const std::string subject = st.message.substr(0, end);
  return "trip:" + st.event + (subject.empty() ? "" : ":" + subject);
}

}  // namespace

bool is_trip_event(const std::string& event) {
  return std::find(kTripEvents.begin(), kTripEvents.end(), event) != kTripEvents.end();
}

std::vector<StatusChange> RigStatus::update(const rigctl::state_t& st) {
  std::vector<StatusChange> out;
  auto clear_trips = [&] {
    for (const auto& id : trips_) out.push_back({true, id, StatusLevel::kInfo, ""});
    trips_.clear();
  };
  // A reset clears every latch; resuming from a hold means its cause has
  // been dealt with: the trips that led there are no longer active.
  if (st.event == "fault_reset") clear_trips();
  if (st.safety_state != safety_state_) {
    if (safety_state_ == "holding" && st.safety_state == "running") clear_trips();
    safety_state_ = st.safety_state;
    out.push_back({false, kStateId, level_of_state(st.safety_state),
                   "rig state " + st.safety_state + " (run " + st.state + ")"});
  }
  if (is_trip_event(st.event)) {
    const std::string id = trip_id(st);
    trips_.insert(id);
    // An interlock leaves the rig faulted: an error; anything the rig rides
    // through (indicate, hold, stop) a warning.
    const StatusLevel level = st.safety_state == "faulted" ? StatusLevel::kError : StatusLevel::kWarning;
    out.push_back({false, id, level, st.event + ": " + st.message});
  }
  return out;
}

}  // namespace rigctl::foxglove
