// The browser console's commands (docs/console.md), over the Foxglove
// connection the page already has for its telemetry.
//
// Why clientPublish on one JSON topic: it is part of the protocol the server
// already speaks, so the page needs no second connection or port, and the
// server accepts exactly one topic from clients, which it can check. A
// Foxglove service would need the services capability and a request
// encoding for a single request type; a second WebSocket endpoint would be
// a second protocol to secure and test.
//
// What the page sends is not trusted: each command is signed in the browser
// (HMAC-SHA256 over the canonical encoding of rt/comms/operator_auth.hpp,
// the key typed by the operator and never sent) and goes, as the LCM bytes
// of an operator_command_t, to the run's CommandIntake: the same verifier,
// replay table, counters, rejection log and queue as `rigctl cmd`. The
// gateway adds exclusive control (console_control.hpp) as the intake's
// admission: once a command is authentic, it reaches the loop if it is a
// stop or a hold (from any console, always) or comes from the holder.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "foxglove/console/console_control.hpp"
#include "foxglove/server/sessions.hpp"
#include "rt/comms/command_intake.hpp"

namespace rigctl::foxglove {

// The one topic clients may publish on: {"id", "sender", "sequence",
// "utime", "command", "value", "tag" (64 hex digits)}; command is an
// operator command, "take_control" (signed like one) or "release_control"
// (unsigned: it only gives up the sender's own control).
inline constexpr const char* kConsoleCommandTopic = "/rigctl/console/command";
// The server's answer to each, to the sending console only: {"id",
// "command", "sequence", "accepted", "reason", "message"}.
inline constexpr const char* kConsoleAnswerTopic = "/rigctl/console/answer";
// Who holds control and since when: a status with this id ("control held
// by SENDER since HH:MM:SS UTC"), removed when nobody does; statuses reach
// consoles that connect later.
inline constexpr const char* kConsoleControlStatus = "console_control";

struct ConsoleOptions {
  // Control held by a console that has answered no ping for this long is
  // released (a closed laptop, a pulled cable without a TCP reset).
  double control_timeout_s = 3.0;
  // Control taken, released, lost: code "console_control" and one line (the
  // run's event log). Called on the server's thread.
  std::function<void(const std::string& code, const std::string& text)> on_event;
};

class ConsoleGateway final : public ClientPublishHandler {
 public:
  // Registers itself with the server's sessions (before the server starts).
  ConsoleGateway(Sessions& server, CommandIntake& intake, ConsoleOptions options = {});

  void on_client_message(uint64_t client, const std::string& topic, const std::string& payload) override;
  void on_client_closed(uint64_t client) override;
  void on_client_silent(uint64_t client, double silent_s) override;

 private:
  struct Answer;
  Answer handle(uint64_t client, const std::string& payload);
  Answer release(uint64_t client);
  Answer take_control(uint64_t client, const operator_command_t& msg);
  Answer command(uint64_t client, const operator_command_t& msg);
  void send_answer(uint64_t client, const Answer& a);
  void lose_control(uint64_t client, const std::string& why);
  void announce_control();

  Sessions& server_;
  CommandIntake& intake_;
  ConsoleOptions options_;
  ConsoleControl control_;  // the server's thread only
  uint32_t answer_channel_ = 0;
};

}  // namespace rigctl::foxglove
