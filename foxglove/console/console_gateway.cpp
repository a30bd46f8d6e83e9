#include "foxglove/console/console_gateway.hpp"

#include <cmath>
#include <ctime>
#include <limits>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "foxglove/server/protocol.hpp"
#include "rt/wall_clock.hpp"

namespace rigctl::foxglove {

using nlohmann::json;

namespace {

const char* const kAnswerSchema = R"({"type":"object","properties":{
  "id":{"type":"number"},"command":{"type":"string"},"sequence":{"type":"number"},
  "accepted":{"type":"boolean"},"reason":{"type":"string"},"message":{"type":"string"}}})";

// An integer field within [lo, hi]; a float, a string or a number out of
// range throws naming the field (a 1e30 must not become INT64_MIN).
int64_t integer_field(const json& j, const char* name, int64_t lo, int64_t hi) {
  const json& v = j.at(name);
  bool ok = false;
  if (v.is_number_unsigned()) ok = v.get<uint64_t>() <= static_cast<uint64_t>(hi);
  else if (v.is_number_integer()) ok = v.get<int64_t>() >= lo && v.get<int64_t>() <= hi;
  if (!ok) throw std::invalid_argument(std::string("field '") + name + "' must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return v.is_number_unsigned() ? static_cast<int64_t>(v.get<uint64_t>()) : v.get<int64_t>();
}

// The message as an operator_command_t; throws std::exception naming the
// field when one is missing or of the wrong type. Not a check of the
// values: the verifier does that.
operator_command_t read_command(const json& j) {
  constexpr int64_t kMax = std::numeric_limits<int64_t>::max();
  operator_command_t msg{};
  msg.version = j.contains("version") ? static_cast<int32_t>(integer_field(j, "version", INT32_MIN, INT32_MAX)) : kOperatorWireVersion;
  msg.sender = j.at("sender").get<std::string>();
  msg.sequence = integer_field(j, "sequence", std::numeric_limits<int64_t>::min(), kMax);
  msg.utime = integer_field(j, "utime", std::numeric_limits<int64_t>::min(), kMax);
  msg.command = j.at("command").get<std::string>();
  if (j.contains("value") && !j["value"].is_number()) throw std::invalid_argument("field 'value' must be a number");
  msg.value = j.value("value", 0.0);
  if (!tag_from_hex(j.at("tag").get<std::string>(), msg.tag)) throw std::invalid_argument("field 'tag': not 64 hex digits");
  return msg;
}

bool always_allowed(OperatorCommandKind k) { return k == OperatorCommandKind::kStop || k == OperatorCommandKind::kHold; }

std::string utc_time(int64_t utime) {
  const std::time_t t = static_cast<std::time_t>(utime / 1'000'000);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char text[32];
  std::strftime(text, sizeof text, "%H:%M:%S UTC", &tm);
  return text;
}

}  // namespace

struct ConsoleGateway::Answer {
  double id = 0;  // the page's own request id, echoed
  std::string command;
  int64_t sequence = 0;
  std::string reason;  // "accepted" or why not
  std::string message;
};

ConsoleGateway::ConsoleGateway(Sessions& server, CommandIntake& intake, ConsoleOptions options)
    : server_(server), intake_(intake), options_(std::move(options)) {
  answer_channel_ = server_.add_channel(kConsoleAnswerTopic, "rigctl.ConsoleAnswer", kAnswerSchema);
  server_.accept_client_publish(this, {kConsoleCommandTopic});
}

void ConsoleGateway::on_client_message(uint64_t client, const std::string& topic, const std::string& payload) {
  if (topic != kConsoleCommandTopic) return;  // the server accepts no other
  send_answer(client, handle(client, payload));
}

ConsoleGateway::Answer ConsoleGateway::handle(uint64_t client, const std::string& payload) {
  Answer a;
  operator_command_t msg{};
  try {
    const json j = json::parse(payload);
    if (j.contains("id") && j["id"].is_number()) a.id = j["id"].get<double>();
    a.command = clip(j.at("command").get<std::string>(), kMaxCommandNameLength);
    if (a.command == "release_control") {
      Answer r = release(client);
      r.id = a.id;
      return r;
    }
    msg = read_command(j);
    a.sequence = msg.sequence;
  } catch (const std::exception& e) {
    DecodedCommand d;
    d.reason = RejectReason::kMalformed;
    d.detail = "unreadable console command: " + clip(e.what(), kMaxEchoedChars);
    intake_.refuse(d, wall_utime_now());
    a.reason = std::string(to_string(d.reason));
    a.message = d.detail;
    return a;
  }
  const Answer verdict = a.command == kTakeControlCommand ? take_control(client, msg) : command(client, msg);
  a.reason = verdict.reason;
  a.message = verdict.message;
  return a;
}

// Unsigned: it can only give up the sender's own control, and is answered
// to the sender alone.
ConsoleGateway::Answer ConsoleGateway::release(uint64_t client) {
  Answer a;
  a.command = "release_control";
  const std::string sender = control_.holder_sender();
  if (!control_.release(client)) {
    a.reason = std::string(to_string(RejectReason::kNotInControl));
    a.message = "this console does not hold control";
    return a;
  }
  if (options_.on_event) options_.on_event("console_control", "console control released by '" + sender + "'");
  announce_control();
  a.reason = "accepted";
  a.message = "control released";
  return a;
}

ConsoleGateway::Answer ConsoleGateway::take_control(uint64_t client, const operator_command_t& msg) {
  const int64_t now = wall_utime_now();
  const bool had = control_.holds(client);
  const DecodedCommand d = intake_.claim(msg, kTakeControlCommand, now, [&](DecodedCommand& c) {
    if (control_.claim(client, c.sender, now)) return true;
    c.reason = RejectReason::kControlHeld;
    c.detail = "control is held by '" + control_.holder_sender() + "' on another console since " +
               utc_time(control_.since_utime());
    return false;
  });
  Answer a;
  a.reason = std::string(to_string(d.reason));
  a.message = d.ok() ? "this console holds control" : d.detail;
  if (d.ok() && !had) {
    if (options_.on_event) options_.on_event("console_control", "console control taken by '" + d.sender + "'");
    announce_control();
  }
  return a;
}

// Stop and hold from any console, every other command from the holder only.
ConsoleGateway::Answer ConsoleGateway::command(uint64_t client, const operator_command_t& msg) {
  Answer a;
  std::vector<uint8_t> bytes;
  try {
    bytes = lcm_encode(msg);
  } catch (const std::exception&) {  // a string LCM cannot carry (an embedded NUL)
    DecodedCommand d;
    d.reason = RejectReason::kMalformed;
    d.detail = "a field holds a NUL character";
    intake_.refuse(d, wall_utime_now());
    return {0, "", 0, std::string(to_string(d.reason)), d.detail};
  }
  const DecodedCommand d = intake_.submit(bytes.data(), bytes.size(), wall_utime_now(), [&](DecodedCommand& c) {
    if (always_allowed(c.command.kind) || control_.holds(client)) return true;
    c.reason = RejectReason::kNotInControl;
    c.detail = control_.holder() ? "control is held by '" + control_.holder_sender() + "' on another console"
                                 : "take control first (stop and hold need no control)";
    return false;
  });
  a.reason = std::string(to_string(d.reason));
  a.message = d.ok() ? "queued for the loop" : d.detail;
  return a;
}

void ConsoleGateway::send_answer(uint64_t client, const Answer& a) {
  const json j{{"id", a.id},         {"command", a.command}, {"sequence", a.sequence},
               {"accepted", a.reason == "accepted"}, {"reason", a.reason},   {"message", a.message}};
  server_.publish_to(client, answer_channel_, static_cast<uint64_t>(wall_utime_now()) * 1000,
                     std::make_shared<const std::string>(j.dump(-1, ' ', false, json::error_handler_t::replace)));  // client bytes may be invalid UTF-8
}

void ConsoleGateway::on_client_closed(uint64_t client) { lose_control(client, "its connection closed"); }

void ConsoleGateway::on_client_silent(uint64_t client, double silent_s) {
  if (silent_s < options_.control_timeout_s) return;
  char why[96];
  std::snprintf(why, sizeof why, "it answered no ping for %.1f s (limit %.1f s)", silent_s, options_.control_timeout_s);
  lose_control(client, why);
}

void ConsoleGateway::lose_control(uint64_t client, const std::string& why) {
  const std::string sender = control_.holder_sender();
  if (!control_.release(client)) return;
  if (options_.on_event) options_.on_event("console_control", "console control of '" + sender + "' released: " + why);
  announce_control();
}

void ConsoleGateway::announce_control() {
  if (control_.holder()) {
    server_.set_status(kConsoleControlStatus, StatusLevel::kInfo,
                       "control held by " + control_.holder_sender() + " since " + utc_time(control_.since_utime()));
  } else {
    server_.remove_status(kConsoleControlStatus);
  }
}

}  // namespace rigctl::foxglove
