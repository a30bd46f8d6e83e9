#include "foxglove/server/protocol.hpp"

#include <algorithm>
#include <cstring>
#include <iterator>

#include <nlohmann/json.hpp>

namespace rigctl::foxglove {

using nlohmann::json;

std::string server_info_json(const std::string& name, const std::map<std::string, std::string>& metadata,
                             const std::string& session_id, bool client_publish) {
  // `parameters`, and clientPublish only when the operator console takes
  // signed commands; no services, no time messages (message times are the
  // samples').
  json capabilities = json::array({"parameters"});
  json out{{"op", "serverInfo"}, {"name", name}, {"metadata", metadata}, {"sessionId", session_id}};
  if (client_publish) {
    capabilities.push_back("clientPublish");
    out["supportedEncodings"] = json::array({"json"});
  }
  out["capabilities"] = capabilities;
  return out.dump();
}

std::string advertise_json(const std::vector<AdvertisedChannel>& channels) {
  json list = json::array();
  for (const auto& c : channels) {
    list.push_back({{"id", c.id},
                    {"topic", c.topic},
                    {"encoding", "json"},
                    {"schemaName", c.schema_name},
                    {"schema", c.schema},
                    {"schemaEncoding", "jsonschema"}});
  }
  return json{{"op", "advertise"}, {"channels", list}}.dump();
}

std::string status_json(const std::string& id, StatusLevel level, const std::string& message) {
  return json{{"op", "status"}, {"level", static_cast<int>(level)}, {"message", message}, {"id", id}}.dump();
}

std::string remove_status_json(const std::vector<std::string>& ids) {
  return json{{"op", "removeStatus"}, {"statusIds", ids}}.dump();
}

std::string parameter_values_json(const std::vector<Parameter>& parameters, const std::string& request_id) {
  json list = json::array();
  for (const auto& p : parameters) list.push_back({{"name", p.name}, {"value", p.value}, {"type", "float64"}});
  json out{{"op", "parameterValues"}, {"parameters", list}};
  if (!request_id.empty()) out["id"] = request_id;
  return out.dump();
}

namespace {

template <typename T>
void put_le(std::string& out, T v) {
  for (std::size_t i = 0; i < sizeof(T); ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}

ClientRequest read_request(const json& j) {
  ClientRequest r;
  r.op = j.at("op").get<std::string>();
  if (r.op == "subscribe") {
    r.kind = ClientRequest::Kind::kSubscribe;
    for (const auto& s : j.at("subscriptions")) {
      r.subscriptions.emplace_back(s.at("id").get<uint32_t>(), s.at("channelId").get<uint32_t>());
    }
  } else if (r.op == "unsubscribe") {
    r.kind = ClientRequest::Kind::kUnsubscribe;
    for (const auto& id : j.at("subscriptionIds")) r.unsubscriptions.push_back(id.get<uint32_t>());
  } else if (r.op == "getParameters" || r.op == "setParameters") {
    r.kind = r.op == "getParameters" ? ClientRequest::Kind::kGetParameters : ClientRequest::Kind::kSetParameters;
    if (j.contains("id") && j["id"].is_string()) r.request_id = j["id"].get<std::string>();
    if (r.kind == ClientRequest::Kind::kGetParameters && j.contains("parameterNames")) {
      r.parameter_names = j["parameterNames"].get<std::vector<std::string>>();
    }
    if (r.kind == ClientRequest::Kind::kSetParameters) {  // answered with the values they keep
      for (const auto& p : j.at("parameters")) r.parameter_names.push_back(p.at("name").get<std::string>());
    }
  } else if (r.op == "advertise") {
    r.kind = ClientRequest::Kind::kAdvertise;
    for (const auto& c : j.at("channels")) {
      r.client_channels.push_back({c.at("id").get<uint32_t>(), c.at("topic").get<std::string>(),
                                   c.at("encoding").get<std::string>(), c.value("schemaName", std::string())});
    }
  } else if (r.op == "unadvertise") {
    r.kind = ClientRequest::Kind::kUnadvertise;
    for (const auto& id : j.at("channelIds")) r.unadvertised.push_back(id.get<uint32_t>());
  } else if (r.op == "subscribeParameterUpdates" ||
             r.op == "unsubscribeParameterUpdates" || r.op == "subscribeConnectionGraph" ||
             r.op == "unsubscribeConnectionGraph" || r.op == "fetchAsset") {
    r.kind = ClientRequest::Kind::kRefused;  // capabilities the server does not offer
  }
  return r;
}

}  // namespace

std::string message_data_frame(uint32_t subscription, uint64_t log_time_ns, const std::string& payload) {
  std::string out;
  out.reserve(1 + 4 + 8 + payload.size());
  out.push_back(static_cast<char>(0x01));
  put_le(out, subscription);
  put_le(out, log_time_ns);
  out += payload;
  return out;
}

ClientRequest parse_client_request(const std::string& text) {
  try {
    const json j = json::parse(text);
    return read_request(j);
  } catch (const std::exception& e) {
    ClientRequest r;
    r.error = e.what();
    return r;
  }
}

std::optional<ClientMessageData> parse_client_message_data(const std::string& frame) {
  if (frame.size() < 5 || static_cast<uint8_t>(frame[0]) != 0x01) return std::nullopt;
  ClientMessageData m;
  for (int i = 0; i < 4; ++i) m.channel |= static_cast<uint32_t>(static_cast<uint8_t>(frame[1 + i])) << (8 * i);
  m.payload = frame.substr(5);
  return m;
}

std::optional<std::string> choose_subprotocol(const std::vector<std::string>& offered) {
  for (const auto& name : offered) {
    if (std::any_of(std::begin(kSubprotocols), std::end(kSubprotocols),
                    [&](const char* ours) { return name == ours; })) {
      return name;
    }
  }
  return std::nullopt;
}

}  // namespace rigctl::foxglove
