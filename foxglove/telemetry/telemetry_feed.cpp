#include "foxglove/telemetry/telemetry_feed.hpp"

#include <memory>

#include <spdlog/spdlog.h>

namespace rigctl::foxglove {

TelemetryFeed::TelemetryFeed(Server& server, const std::string& channel_prefix)
    : server_(server), topics_(channel_prefix) {}

void TelemetryFeed::on_message(const std::string& channel, int64_t, const uint8_t* data, std::size_t size) noexcept {
  const auto topic = topics_.topic_of(channel);
  if (!topic) return;  // operator commands and acks are not telemetry
  try {
    handle(*topic, channel, data, size);
  } catch (const std::exception& e) {
    // Never into the publisher: a failure here must not cost the run log.
    // A lasting fault would fail every message (1200 a second): said once
    // per 10000, as the publisher says its own publish failures.
    if (unserved_.fetch_add(1, std::memory_order_relaxed) % 10000 == 0) {
      spdlog::warn("foxglove: message on {} not served: {} ({} so far)", channel, e.what(), unserved_.load());
    }
  }
}

void TelemetryFeed::handle(TelemetryTopic topic, const std::string& channel, const uint8_t* data, std::size_t size) {
  auto known = channel_ids_.find(topic);
  // Decoding costs a little on the publisher thread: only for a channel
  // still to be advertised, one a client listens to, and the state channel
  // (statuses go to every client). One look at the subscribers per message
  // (each takes the server's lock); a channel advertised just now has none.
  const bool advertised = known != channel_ids_.end();
  const bool subscribed = advertised && server_.has_subscribers(known->second);
  if (advertised && !subscribed && topic != TelemetryTopic::kState) return;
  const auto message = decode_telemetry(topic, data, size);
  if (!message) {
    undecodable_.fetch_add(1);
    return;
  }
  if (!advertised) {
    known = channel_ids_.emplace(topic, server_.add_channel(channel, schema_name(topic), json_schema(*message))).first;
  }
  if (subscribed) {
    server_.publish(known->second, log_time_ns(*message), std::make_shared<const std::string>(to_json(*message)));
  }
  if (const auto* state = std::get_if<rigctl::state_t>(&*message)) {
    for (const auto& change : status_.update(*state)) {
      if (change.remove) {
        server_.remove_status(change.id);
      } else {
        server_.set_status(change.id, change.level, change.message);
      }
    }
  }
}

}  // namespace rigctl::foxglove
