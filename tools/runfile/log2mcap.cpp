// LCM log -> MCAP: one pass over the log. A channel's first message defines
// its schema (as on the live server); every message becomes its JSON.
#include "tools/runfile/log2mcap.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include <lcm/lcm-cpp.hpp>

#include "foxglove/mcap/mcap_writer.hpp"
#include "foxglove/telemetry/telemetry_json.hpp"
#include "tools/runfile/lcm_log.hpp"

namespace rigctl {

namespace {

using foxglove::TelemetryTopic;

int64_t file_size(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 ? static_cast<int64_t>(st.st_size) : -1;
}

class McapChannels {
 public:
  explicit McapChannels(mcap::McapWriter& writer) : writer_(writer) {}
  uint16_t channel_for(TelemetryTopic topic, const std::string& lcm_channel, const foxglove::TelemetryMessage& first) {
    const auto it = ids_.find(topic);
    if (it != ids_.end()) return it->second;
    const uint16_t schema = writer_.add_schema(foxglove::schema_name(topic), "jsonschema", foxglove::json_schema(first));
    return ids_[topic] = writer_.add_channel(schema, lcm_channel, "json");
  }

 private:
  mcap::McapWriter& writer_;
  std::map<TelemetryTopic, uint16_t> ids_;
};

}  // namespace

Log2McapResult log_to_mcap(const std::string& lcm_log_path, const std::string& mcap_path,
                           const std::string& channel_prefix) {
  check_is_lcm_log(lcm_log_path, "log2mcap");
  lcm::LogFile log(lcm_log_path, "r");
  if (!log.good()) {
    throw std::runtime_error("log2mcap: '" + lcm_log_path + "': cannot open as LCM log: " + std::strerror(errno));
  }
  mcap::McapWriter writer(mcap_path, "", "rigctl log2mcap");
  McapChannels channels(writer);
  const foxglove::TelemetryTopics topics(channel_prefix);
  Log2McapResult result;
  long end_of_last_event = 0;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    end_of_last_event = std::ftell(log.getFilePtr());
    const auto topic = topics.topic_of(ev->channel);
    const auto message = topic ? foxglove::decode_telemetry(*topic, static_cast<const uint8_t*>(ev->data),
                                                            static_cast<std::size_t>(ev->datalen))
                               : std::nullopt;
    if (!message) {
      ++result.skipped;
      continue;
    }
    const uint16_t id = channels.channel_for(*topic, ev->channel, *message);
    const uint64_t t = foxglove::log_time_ns(*message);
    writer.add_message(id, t, t, foxglove::to_json(*message));
    ++result.messages;
    ++result.per_channel[ev->channel];
  }
  const int64_t size = file_size(lcm_log_path);
  if (size > end_of_last_event) {
    result.warning = "the log ends in " + std::to_string(size - end_of_last_event) +
                     " bytes that are no whole event (a run cut short?): the MCAP holds the " +
                     std::to_string(result.messages) + " messages before them";
  }
  writer.close();
  result.chunks = writer.statistics().chunk_count;
  return result;
}

}  // namespace rigctl
