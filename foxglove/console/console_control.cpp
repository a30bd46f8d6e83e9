#include "foxglove/console/console_control.hpp"

#include <cstdlib>

namespace rigctl::foxglove {

ControlAnswer ConsoleControl::claim(uint64_t client, const operator_command_t& msg, int64_t now_utime) {
  // The receiver's checks in its order: form, version, tag, staleness,
  // replay; nothing but the tag is trusted before it verifies.
  if (!valid_sender_id(msg.sender) || msg.sequence <= 0 || msg.command != kTakeControlCommand || msg.value != 0.0) {
    return {std::string(to_string(RejectReason::kMalformed)), "a take_control claim needs a valid sender, a sequence > 0 and value 0"};
  }
  if (msg.version != kOperatorWireVersion) {
    return {std::string(to_string(RejectReason::kBadVersion)), "version " + std::to_string(msg.version) + " (expected 1)"};
  }
  const auto bytes = canonical_bytes(msg);
  if (!tags_equal(hmac_sha256(key_, bytes.data(), bytes.size()), msg.tag)) {
    return {std::string(to_string(RejectReason::kBadTag)), "the tag does not verify: another key, or the command was altered"};
  }
  if (std::llabs(now_utime - msg.utime) > max_age_us_) {
    return {std::string(to_string(RejectReason::kStale)), "utime " + std::to_string(msg.utime) + " is " +
                                      std::to_string((now_utime - msg.utime) / 1000) + " ms from the rig's clock"};
  }
  auto& last = last_claim_sequence_[msg.sender];
  if (msg.sequence <= last) {
    return {std::string(to_string(RejectReason::kReplayed)), "sequence " + std::to_string(msg.sequence) + " not above the last claim " +
                                         std::to_string(last)};
  }
  if (holder_ && *holder_ != client) {
    // The claim is authentic: its sequence is used up all the same.
    last = msg.sequence;
    return {kControlHeldReason, "control is held by '" + holder_sender_ + "' on another console"};
  }
  last = msg.sequence;
  holder_ = client;
  holder_sender_ = msg.sender;
  return {};
}

void ConsoleControl::release(uint64_t client) {
  if (!holds(client)) return;
  holder_.reset();
  holder_sender_.clear();
}

}  // namespace rigctl::foxglove
