// Feeds a Foxglove server from rigctl's telemetry messages: every telemetry
// channel is advertised under its LCM channel name with its JSON schema when
// its first message arrives, messages go to the clients subscribed to them,
// and the STATE channel drives the status messages (foxglove/telemetry/rig_status.hpp).
// As the publisher's tap (`rigctl run --ws`) it runs on the publisher thread;
// the bridge calls it from its LCM thread. One thread at a time.
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <string>

#include "foxglove/server/server.hpp"
#include "foxglove/telemetry/rig_status.hpp"
#include "foxglove/telemetry/telemetry_json.hpp"
#include "rt/comms/telemetry_tap.hpp"

namespace rigctl::foxglove {

class TelemetryFeed final : public TelemetryTap {
 public:
  TelemetryFeed(Server& server, const std::string& channel_prefix);

  void on_message(const std::string& channel, int64_t utime, const uint8_t* data, std::size_t size) noexcept override;

  int64_t undecodable() const { return undecodable_.load(); }  // messages that did not decode as their channel's type

 private:
  void handle(TelemetryTopic topic, const std::string& channel, const uint8_t* data, std::size_t size);

  Server& server_;
  TelemetryTopics topics_;
  std::map<TelemetryTopic, uint32_t> channel_ids_;  // advertised so far
  RigStatus status_;
  std::atomic<int64_t> undecodable_{0};
  std::atomic<int64_t> unserved_{0};  // messages whose serving threw (warned once per 10000)
};

}  // namespace rigctl::foxglove
