// Exclusive control of the rig from the browser console (docs/console.md):
// one console at a time may send commands, the others watch, as on an
// industrial station. Taking control is itself a signed command: the
// canonical operator command encoding (rt/comms/operator_auth.hpp) with the
// command "take_control", checked here for its tag, its staleness and a
// sequence above the sender's last claim. It never reaches the state
// machine: it only says which connection may send the commands that do.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include "rigctl/operator_command_t.hpp"
#include "rt/comms/operator_auth.hpp"

namespace rigctl::foxglove {

inline constexpr const char* kTakeControlCommand = "take_control";

// Refused: another connection holds control (it must release it, or close).
inline constexpr const char* kControlHeldReason = "control_held";

struct ControlAnswer {
  std::string reason = "accepted";  // else to_string(RejectReason) or kControlHeldReason
  std::string detail;               // why not, naming the field
  bool ok() const { return reason == "accepted"; }
};

class ConsoleControl {
 public:
  // The rig's key and staleness window (the command receiver's own).
  ConsoleControl(const OperatorKey& key, int64_t max_age_us) : key_(key), max_age_us_(max_age_us) {}

  // A claim by connection `client`: on success it holds control. While
  // another connection holds it the claim is refused (kControlHeldReason):
  // control passes only when its holder releases it or disconnects.
  ControlAnswer claim(uint64_t client, const operator_command_t& msg, int64_t now_utime);
  bool holds(uint64_t client) const { return holder_ && *holder_ == client; }
  // Its holder gives control up, or the connection is gone.
  void release(uint64_t client);
  std::optional<uint64_t> holder() const { return holder_; }
  const std::string& holder_sender() const { return holder_sender_; }

 private:
  const OperatorKey& key_;
  int64_t max_age_us_;
  std::optional<uint64_t> holder_;
  std::string holder_sender_;
  std::map<std::string, int64_t> last_claim_sequence_;  // authentic senders only
};

}  // namespace rigctl::foxglove
