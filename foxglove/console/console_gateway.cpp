#include "foxglove/console/console_gateway.hpp"
#include "rt/wall_clock.hpp"

#include <chrono>
#include <cmath>

#include <nlohmann/json.hpp>

namespace rigctl::foxglove {

using nlohmann::json;

namespace {

const char* const kAnswerSchema = R"({"type":"object","properties":{
  "id":{"type":"number"},"command":{"type":"string"},"sequence":{"type":"number"},
  "accepted":{"type":"boolean"},"reason":{"type":"string"},"message":{"type":"string"}}})";

bool read_tag(const std::string& hex, uint8_t* out) {
  if (hex.size() != 2 * kOperatorTagBytes) return false;
  for (std::size_t i = 0; i < kOperatorTagBytes; ++i) {
    unsigned v = 0;
    for (int k = 0; k < 2; ++k) {
      const char c = hex[2 * i + k];
      const int d = c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : c >= 'A' && c <= 'F' ? c - 'A' + 10 : -1;
      if (d < 0) return false;
      v = v * 16 + static_cast<unsigned>(d);
    }
    out[i] = static_cast<uint8_t>(v);
  }
  return true;
}

// The message as an operator_command_t; throws std::exception naming the
// field when one is missing or of the wrong type. Not a check of the
// values: the verifier does that.
operator_command_t read_command(const json& j) {
  operator_command_t msg{};
  msg.version = j.value("version", kOperatorWireVersion);
  msg.sender = j.at("sender").get<std::string>();
  msg.sequence = j.at("sequence").get<int64_t>();
  msg.utime = j.at("utime").get<int64_t>();
  msg.command = j.at("command").get<std::string>();
  msg.value = j.value("value", 0.0);
  if (!read_tag(j.at("tag").get<std::string>(), msg.tag)) throw std::invalid_argument("tag: not 64 hex digits");
  return msg;
}

}  // namespace

struct ConsoleGateway::Answer {
  double id = 0;  // the page's own request id, echoed
  std::string command;
  int64_t sequence = 0;
  std::string reason;  // "accepted" or why not
  std::string message;
};

ConsoleGateway::ConsoleGateway(Server& server, CommandReceiver& receiver)
    : server_(server), receiver_(receiver), control_(receiver.key(), receiver.policy().max_age_us) {
  answer_channel_ = server_.add_channel(kConsoleAnswerTopic, "rigctl.ConsoleAnswer", kAnswerSchema);
  server_.accept_client_publish(this, {kConsoleCommandTopic});
}

void ConsoleGateway::on_client_message(uint64_t client, const std::string& topic, const std::string& payload) {
  if (topic != kConsoleCommandTopic) return;  // the server accepts no other
  send_answer(client, handle(client, payload));
}

ConsoleGateway::Answer ConsoleGateway::handle(uint64_t client, const std::string& payload) {
  Answer a;
  json j;
  operator_command_t msg{};
  try {
    j = json::parse(payload);
    if (j.contains("id") && j["id"].is_number()) a.id = j["id"].get<double>();
    a.command = j.at("command").get<std::string>();
    if (a.command == "release_control") {
      control_.release(client);
      announce_control();
      a.reason = "accepted";
      a.message = "control released";
      return a;
    }
    msg = read_command(j);
    a.sequence = msg.sequence;
  } catch (const std::exception& e) {
    a.reason = std::string(to_string(RejectReason::kMalformed));
    a.message = std::string("unreadable command: ") + e.what();
    return a;
  }
  if (a.command == kTakeControlCommand) {
    const ControlAnswer c = control_.claim(client, msg, wall_utime_now());
    a.reason = c.reason;
    a.message = c.ok() ? "this console holds control" : c.detail;
    if (c.ok()) announce_control();
    return a;
  }
  if (!control_.holds(client)) {
    a.reason = kNotInControlReason;
    a.message = control_.holder() ? "control is held by '" + control_.holder_sender() + "' on another console"
                                  : "take control first";
    return a;
  }
  const auto bytes = lcm_encode(msg);
  const DecodedCommand d = receiver_.submit(bytes.data(), bytes.size());
  a.reason = std::string(to_string(d.reason));
  a.message = d.ok() ? "queued for the loop" : d.detail;
  return a;
}

void ConsoleGateway::send_answer(uint64_t client, const Answer& a) {
  const json j{{"id", a.id},         {"command", a.command}, {"sequence", a.sequence},
               {"accepted", a.reason == "accepted"}, {"reason", a.reason},   {"message", a.message}};
  server_.publish_to(client, answer_channel_, static_cast<uint64_t>(wall_utime_now()) * 1000,
                     std::make_shared<const std::string>(j.dump()));
}

void ConsoleGateway::on_client_closed(uint64_t client) {
  if (!control_.holds(client)) return;
  control_.release(client);
  announce_control();
}

void ConsoleGateway::announce_control() {
  if (control_.holder()) {
    server_.set_status(kConsoleControlStatus, StatusLevel::kInfo, "control held by " + control_.holder_sender());
  } else {
    server_.remove_status(kConsoleControlStatus);
  }
}

}  // namespace rigctl::foxglove
