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
// of an operator_command_t, through CommandReceiver::submit(): the same
// verifier, replay table, rejection log and queue as `rigctl cmd`. The
// gateway adds exclusive control (console_control.hpp) in front of it.
#pragma once

#include <cstdint>
#include <string>

#include "foxglove/console/console_control.hpp"
#include "foxglove/server/server.hpp"
#include "rt/comms/command_receiver.hpp"

namespace rigctl::foxglove {

// The one topic clients may publish on: {"id", "sender", "sequence",
// "utime", "command", "value", "tag" (64 hex digits)}; command is an
// operator command, "take_control" (signed like one) or "release_control"
// (unsigned: it only gives up the sender's own control).
inline constexpr const char* kConsoleCommandTopic = "/rigctl/console/command";
// The server's answer to each, to the sending console only: {"id",
// "command", "sequence", "accepted", "reason", "message"}.
inline constexpr const char* kConsoleAnswerTopic = "/rigctl/console/answer";
// Who holds control: a status with this id ("control held by SENDER"),
// removed when nobody does; statuses reach consoles that connect later.
inline constexpr const char* kConsoleControlStatus = "console_control";
// A console that sends a command without holding control.
inline constexpr const char* kNotInControlReason = "not_in_control";

class ConsoleGateway final : public ClientPublishHandler {
 public:
  // Registers itself with the server (before server.start()).
  ConsoleGateway(Server& server, CommandReceiver& receiver);

  void on_client_message(uint64_t client, const std::string& topic, const std::string& payload) override;
  void on_client_closed(uint64_t client) override;

 private:
  struct Answer;
  Answer handle(uint64_t client, const std::string& payload);
  void send_answer(uint64_t client, const Answer& a);
  void announce_control();

  Server& server_;
  CommandReceiver& receiver_;
  ConsoleControl control_;  // the server's thread only
  uint32_t answer_channel_ = 0;
};

}  // namespace rigctl::foxglove
