// The Foxglove WebSocket protocol's messages as bytes: the JSON operations
// the server sends, the binary message-data frame, and the parsing of what a
// client sends. Pure functions, no sockets (docs/foxglove.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "foxglove/server/server.hpp"

namespace rigctl::foxglove {

struct AdvertisedChannel {
  uint32_t id = 0;
  std::string topic;
  std::string schema_name;
  std::string schema;  // JSON Schema text
};

// client_publish: offer the clientPublish capability (JSON encoding only).
// A channel a client advertised to publish on (clientPublish).
struct ClientChannel {
  uint32_t id = 0;
  std::string topic;
  std::string encoding;
  std::string schema_name;
};

std::string server_info_json(const std::string& name, const std::map<std::string, std::string>& metadata,
                             const std::string& session_id, bool client_publish = false);
std::string advertise_json(const std::vector<AdvertisedChannel>& channels);
std::string status_json(const std::string& id, StatusLevel level, const std::string& message);
std::string remove_status_json(const std::vector<std::string>& ids);
// parameterValues; request_id "" leaves out `id`.
std::string parameter_values_json(const std::vector<Parameter>& parameters, const std::string& request_id);

// What the server echoes of a client's text (an op, a topic, a parse error
// quoting the input) is cut to this many bytes: a client's 30 MB string must
// not come back as a 30 MB status.
inline constexpr std::size_t kMaxEchoedChars = 200;
// `text` cut to at most max_chars bytes (not inside a UTF-8 character), "..." added when cut.
std::string clip(const std::string& text, std::size_t max_chars);

// Binary opcode 0x01: subscription id, receive (log) time, payload; little endian.
std::string message_data_frame(uint32_t subscription, uint64_t log_time_ns, const std::string& payload);

// What a client asked for, parsed from one text message. Ids must be
// integers in the uint32 range (else kUnknown with the error naming the field).
struct ClientRequest {
  enum class Kind { kSubscribe, kUnsubscribe, kGetParameters, kSetParameters, kAdvertise, kUnadvertise, kRefused, kUnknown };
  Kind kind = Kind::kUnknown;
  std::vector<std::pair<uint32_t, uint32_t>> subscriptions;  // (subscription id, channel id)
  std::vector<uint32_t> unsubscriptions;                     // subscription ids
  std::vector<std::string> parameter_names;                  // get: empty for all; set: the names to be set
  std::vector<ClientChannel> client_channels;                // advertise: the channels the client will publish on
  std::vector<uint32_t> unadvertised;                        // unadvertise: client channel ids
  std::string request_id;
  std::string op;     // as sent
  std::string error;  // why the message could not be read ("" when it could)
};
ClientRequest parse_client_request(const std::string& text);

// A client's binary message: opcode 0x01 (message data), then its channel
// id (uint32 LE) and the payload. nullopt for any other opcode or a frame
// too short to hold the id.
struct ClientMessageData {
  uint32_t channel = 0;
  std::string payload;
};
std::optional<ClientMessageData> parse_client_message_data(const std::string& frame);

// The first subprotocol the client offered that the server speaks, if any.
std::optional<std::string> choose_subprotocol(const std::vector<std::string>& offered);

}  // namespace rigctl::foxglove
