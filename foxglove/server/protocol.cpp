#include "foxglove/server/protocol.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <iterator>

#include <nlohmann/json.hpp>

namespace rigctl::foxglove {

using nlohmann::json;

// Every message's text: a client's bytes quoted in it (a parse error, a
// topic) may be invalid UTF-8, which nlohmann's dump() throws on by
// default; such bytes become U+FFFD instead.
namespace {
std::string to_text(const json& j) { return j.dump(-1, ' ', false, json::error_handler_t::replace); }
}  // namespace

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
  return to_text(out);
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
  return to_text(json{{"op", "advertise"}, {"channels", list}});
}

std::string status_json(const std::string& id, StatusLevel level, const std::string& message) {
  return to_text(json{{"op", "status"}, {"level", static_cast<int>(level)}, {"message", message}, {"id", id}});
}

std::string remove_status_json(const std::vector<std::string>& ids) {
  return to_text(json{{"op", "removeStatus"}, {"statusIds", ids}});
}

std::string parameter_values_json(const std::vector<Parameter>& parameters, const std::string& request_id) {
  json list = json::array();
  for (const auto& p : parameters) list.push_back({{"name", p.name}, {"value", p.value}, {"type", "float64"}});
  json out{{"op", "parameterValues"}, {"parameters", list}};
  if (!request_id.empty()) out["id"] = request_id;
  return to_text(out);
}

namespace {

template <typename T>
void put_le(std::string& out, T v) {
  for (std::size_t i = 0; i < sizeof(T); ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}

// An id of the protocol: an integer in the uint32 range, or a request the
// server refuses (2^40 must not become 0, nor -1 become 4294967295).
uint32_t uint32_field(const json& j, const char* name) {
  const json& v = j.at(name);
  const bool in_range = v.is_number_unsigned() ? v.get<uint64_t>() <= UINT32_MAX
                                               : v.is_number_integer() && v.get<int64_t>() >= 0 && v.get<int64_t>() <= UINT32_MAX;
  if (!in_range) throw std::invalid_argument(std::string("'") + name + "' must be an integer in 0..4294967295, not " + clip(to_text(v), 40));
  return static_cast<uint32_t>(v.get<uint64_t>());
}

uint32_t uint32_value(const json& v, const char* what) {
  return uint32_field(json{{what, v}}, what);
}

ClientRequest read_request(const json& j) {
  ClientRequest r;
  r.op = clip(j.at("op").get<std::string>(), 64);
  if (r.op == "subscribe") {
    r.kind = ClientRequest::Kind::kSubscribe;
    for (const auto& s : j.at("subscriptions")) {
      r.subscriptions.emplace_back(uint32_field(s, "id"), uint32_field(s, "channelId"));
    }
  } else if (r.op == "unsubscribe") {
    r.kind = ClientRequest::Kind::kUnsubscribe;
    for (const auto& id : j.at("subscriptionIds")) r.unsubscriptions.push_back(uint32_value(id, "subscriptionIds"));
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
      r.client_channels.push_back({uint32_field(c, "id"), c.at("topic").get<std::string>(),
                                   c.at("encoding").get<std::string>(), c.value("schemaName", std::string())});
    }
  } else if (r.op == "unadvertise") {
    r.kind = ClientRequest::Kind::kUnadvertise;
    for (const auto& id : j.at("channelIds")) r.unadvertised.push_back(uint32_value(id, "channelIds"));
  } else if (r.op == "subscribeParameterUpdates" ||
             r.op == "unsubscribeParameterUpdates" || r.op == "subscribeConnectionGraph" ||
             r.op == "unsubscribeConnectionGraph" || r.op == "fetchAsset") {
    r.kind = ClientRequest::Kind::kRefused;  // capabilities the server does not offer
  }
  return r;
}

}  // namespace

std::string clip(const std::string& text, std::size_t max_chars) {
  if (text.size() <= max_chars) return text;
  std::size_t n = max_chars;
  while (n > 0 && (static_cast<unsigned char>(text[n]) & 0xC0) == 0x80) --n;  // not inside a UTF-8 character
  return text.substr(0, n) + "...";
}

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
    r.error = clip(e.what(), kMaxEchoedChars);  // a parse error quotes the client's text
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
