// rigctl's telemetry as JSON: each LCM message of a telemetry channel becomes
// one JSON object whose fields are the run-file column names in SI units
// (rt/comms/telemetry_columns.hpp), with a JSON Schema that describes it.
// One piece of code for the live server, the bridge and the MCAP export, so
// all three show the same channels, schemas and messages (docs/foxglove.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <variant>

#include "rigctl/channels_t.hpp"
#include "rigctl/command_t.hpp"
#include "rigctl/controller_t.hpp"
#include "rigctl/driver_status_t.hpp"
#include "rigctl/procedure_t.hpp"
#include "rigctl/sample_t.hpp"
#include "rigctl/state_t.hpp"
#include "rigctl/timing_t.hpp"
#include "rt/comms/telemetry_publisher.hpp"

namespace rigctl::foxglove {

// kChannels: the control channels after the first, on rigs with several
// (<prefix>CHANNELS, lcmtypes/rigctl_channels_t.lcm; a one-channel rig never
// publishes it, so its clients see what they always saw).
enum class TelemetryTopic { kSample, kCommand, kController, kTiming, kState, kDriver, kProcedure, kChannels };
inline constexpr TelemetryTopic kTelemetryTopics[] = {TelemetryTopic::kSample,     TelemetryTopic::kCommand,
                                                      TelemetryTopic::kController, TelemetryTopic::kTiming,
                                                      TelemetryTopic::kState,      TelemetryTopic::kDriver,
                                                      TelemetryTopic::kProcedure,  TelemetryTopic::kChannels};

using TelemetryMessage = std::variant<rigctl::sample_t, rigctl::command_t, rigctl::controller_t, rigctl::timing_t,
                                      rigctl::state_t, rigctl::driver_status_t, rigctl::procedure_t,
                                      rigctl::channels_t>;

// The telemetry channels of one channel prefix (e.g. RIGCTL_SAMPLE).
class TelemetryTopics {
 public:
  explicit TelemetryTopics(const std::string& prefix) : channels_(prefix) {}
  // nullopt for a channel that is not telemetry (operator commands and acks).
  std::optional<TelemetryTopic> topic_of(const std::string& channel) const;
  const std::string& channel_of(TelemetryTopic topic) const;

 private:
  TelemetryChannels channels_;
};

// "rigctl.Sample", ...: the schema names clients show.
std::string schema_name(TelemetryTopic topic);

// nullopt when the bytes are not a message of the topic's type.
std::optional<TelemetryMessage> decode_telemetry(TelemetryTopic topic, const uint8_t* data, std::size_t size);

// The message's time stamp [ns since the epoch]: the sample's time for the
// tick's messages (utime = the run's start + rig time).
uint64_t log_time_ns(const TelemetryMessage& message);

// The JSON object of a message, and the JSON Schema its shape satisfies
// (names from the message: the first message of a channel defines it).
std::string to_json(const TelemetryMessage& message);
std::string json_schema(const TelemetryMessage& message);

}  // namespace rigctl::foxglove
