// Authentication of operator commands (issue 7). Anyone who can put a
// multicast packet on the rig network could otherwise arm or start a rig, so a
// command acts only if
//   * its HMAC-SHA256 tag verifies with the rig's key (a shared secret in a
//     file readable only by the service and the operators' `rigctl cmd`),
//   * its sequence number is above the last one accepted from its sender
//     (replay), and
//   * its utime is within a window of the rig's clock (staleness), and not
//     before the receiver started. Sequence numbers alone are not enough:
//     the table of last sequences lives in memory, so after a controller
//     restart it is empty and every command ever captured would be accepted
//     once more. The window limits that to commands captured in the last few
//     seconds, and refusing what was signed before the start closes that gap
//     too (simpler and safer than persisting the table: no file to lose,
//     corrupt or roll back, and nothing written per command).
// Wire format and canonical (MACed) encoding: docs/operator-commands.md and
// canonical_bytes() below.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "rigctl/operator_ack_t.hpp"
#include "rigctl/operator_command_t.hpp"
#include "rt/safety/operator_command.hpp"

namespace rigctl {

inline constexpr int32_t kOperatorWireVersion = 1;
inline constexpr std::size_t kOperatorKeyMinBytes = 32;
inline constexpr std::size_t kOperatorKeyMaxBytes = 4096;  // a key file larger than this is a mistake
inline constexpr std::size_t kOperatorTagBytes = 32;
inline constexpr std::size_t kMaxSenderLength = 64;
inline constexpr std::size_t kMaxCommandNameLength = 32;

using OperatorTag = std::array<uint8_t, kOperatorTagBytes>;

// The shared secret: the whole content of the key file, byte for byte (a
// trailing newline is part of the key). Wiped from memory on destruction.
class OperatorKey {
 public:
  // Throws std::invalid_argument when shorter than kOperatorKeyMinBytes.
  static OperatorKey from_bytes(const void* data, std::size_t size);
  OperatorKey(const OperatorKey&) = default;
  OperatorKey(OperatorKey&&) = default;
  OperatorKey& operator=(const OperatorKey&) = default;
  OperatorKey& operator=(OperatorKey&&) = default;
  ~OperatorKey();

  const uint8_t* data() const { return bytes_.data(); }
  std::size_t size() const { return bytes_.size(); }

 private:
  OperatorKey() = default;
  std::vector<uint8_t> bytes_;
};

// Reads a key file. Throws std::runtime_error naming the file and the problem:
// missing/unreadable, not a regular file, readable or writable by group or
// others (mode shown; "chmod 600" it), owned by another user than the
// process's (or root), in a folder that another user may write to (group or
// others writable without the sticky bit, or owned by another user), shorter
// than 32 bytes, larger than 4 KiB.
OperatorKey load_operator_key(const std::string& path);

// HMAC-SHA256 (OpenSSL libcrypto).
OperatorTag hmac_sha256(const OperatorKey& key, const uint8_t* data, std::size_t size);
// Constant-time comparison (CRYPTO_memcmp): the time taken does not tell an
// attacker how many leading bytes of a guessed tag were right.
bool tags_equal(const OperatorTag& a, const uint8_t* b);
// A tag written as 64 hex digits (the console's JSON) into out[32], by
// libcrypto's decoder; false for anything else (no separators, no prefix).
bool tag_from_hex(std::string_view hex, uint8_t* out);

// Canonical encodings, the bytes the tags are computed over (all integers
// big-endian, strings as a uint32 byte count then the bytes, no terminator):
//   command: "rigctl.operator_command.v1" 0x00, version int32, sender string,
//            sequence int64, utime int64, command string, value as the IEEE-754
//            binary64 bit pattern (uint64)
//   ack:     "rigctl.operator_ack.v1" 0x00, version int32, utime int64, sender
//            string, sequence int64, accepted uint8 (0/1), reason string,
//            message string
// Explicit rather than the LCM encoding so that another implementation can
// produce it without LCM, and so that the leading label keeps a command's tag
// from ever verifying as an ack's (or another version's).
std::vector<uint8_t> canonical_bytes(const operator_command_t& msg);
std::vector<uint8_t> canonical_bytes(const operator_ack_t& msg);

// Sets msg.tag from the other fields.
void sign(operator_command_t& msg, const OperatorKey& key);
void sign(operator_ack_t& msg, const OperatorKey& key);
bool tag_valid(const operator_ack_t& msg, const OperatorKey& key);

// The LCM encoding (what goes on the bus).
std::vector<uint8_t> lcm_encode(const operator_command_t& msg);
std::vector<uint8_t> lcm_encode(const operator_ack_t& msg);

// Decodes the LCM bytes of an ack with the same bounds-checked reader as
// commands (false for anything malformed; never throws). The tag is not
// checked here: tag_valid().
bool decode_operator_ack(const void* data, std::size_t size, operator_ack_t& ack) noexcept;

// Wire name of a kind ("hydraulics_low", ...) and back; false if unknown.
bool parse_command_name(std::string_view name, OperatorCommandKind& kind);

// Sender ids: 1-64 characters of [A-Za-z0-9_.@-] (they also name the
// sender's sequence state file).
bool valid_sender_id(std::string_view sender);

enum class RejectReason : uint8_t {
  kNone = 0,        // accepted
  kMalformed,       // not a well-formed operator_command_t (size, LCM fingerprint, strings, sender id, sequence <= 0)
  kBadVersion,      // version is not kOperatorWireVersion
  kBadTag,          // HMAC does not verify: forged, corrupted or the wrong key
  kStale,           // utime outside the window around the rig's clock
  kReplayed,        // sequence not above the last accepted from this sender
  kUnknownCommand,  // authentic, but not a command this rig knows
  kBadValue,        // value not finite, or not 0 for a command without a value
  kOutOfLimits,     // setpoint outside the configured limits (or none configured)
  kTooManySenders,  // replay table full of recently active senders
  kQueueFull,       // accepted but the loop's queue was full (CommandReceiver only)
  kNotInControl,    // authentic, from a console that does not hold control (foxglove/console)
  kControlHeld,     // an authentic claim of control while another console holds it
  kCount
};
inline constexpr std::size_t kRejectReasonCount = static_cast<std::size_t>(RejectReason::kCount);

// "accepted", "malformed", "bad_version", "bad_tag", "stale", "replayed",
// "unknown_command", "bad_value", "out_of_limits", "too_many_senders",
// "queue_full", "not_in_control", "control_held".
std::string_view to_string(RejectReason r);

struct CommandPolicy {
  // Largest |rig clock - command utime| [us]. Both ways: a command dated in
  // the future would otherwise stay replayable after a restart for longer.
  int64_t max_age_us = 2'000'000;
  // Setpoint commands must lie in [setpoint_min, setpoint_max] (SI, the held
  // setpoint's unit). NaN: not configured, every setpoint command is refused.
  double setpoint_min = std::numeric_limits<double>::quiet_NaN();
  double setpoint_max = std::numeric_limits<double>::quiet_NaN();
  std::string setpoint_unit;  // for messages only, e.g. "m"
  // Commands dated before this [us since the epoch] are refused as stale:
  // the receiver's start, so that nothing captured before a restart is
  // taken after it (0: no such bound).
  int64_t not_before_utime = 0;
};

struct DecodedCommand {
  RejectReason reason = RejectReason::kMalformed;
  std::string detail;   // one line naming the field and value at fault; "" when accepted
  std::string sender;   // as received ("" when it could not be decoded); authentic only when ok()
  int64_t sequence = 0; // as received
  int64_t utime = 0;    // as received
  OperatorCommand command{};  // valid only when ok()
  bool ok() const { return reason == RejectReason::kNone; }
};

// Decodes and checks one raw LCM message (the bytes of operator_command_t):
// structure, version, tag, staleness against now_utime, command name and
// value. Everything but the replay check, which needs state (see
// OperatorVerifier). Pure and total: any bytes, any size, never throws or
// crashes; garbage gives kMalformed. Fuzzers call this, e.g.
//   static const auto key = OperatorKey::from_bytes(std::string(32, 'k').data(), 32);
//   decode_operator_command(data, size, key, CommandPolicy{}, 0);
DecodedCommand decode_operator_command(const void* data, std::size_t size, const OperatorKey& key,
                                       const CommandPolicy& policy, int64_t now_utime) noexcept;

// Per-reason counters, readable from any thread.
class RejectCounters {
 public:
  void add(RejectReason r) noexcept { counts_[static_cast<std::size_t>(r)].fetch_add(1, std::memory_order_relaxed); }
  uint64_t get(RejectReason r) const noexcept { return counts_[static_cast<std::size_t>(r)].load(std::memory_order_relaxed); }
  // Moves one count from `from` to `to` (an accepted command the receiver
  // could not queue becomes queue_full).
  void move(RejectReason from, RejectReason to) noexcept {
    counts_[static_cast<std::size_t>(from)].fetch_sub(1, std::memory_order_relaxed);
    add(to);
  }
  uint64_t accepted() const noexcept { return get(RejectReason::kNone); }
  uint64_t rejected() const noexcept;  // every reason but kNone

 private:
  std::array<std::atomic<uint64_t>, kRejectReasonCount> counts_{};
};

// decode_operator_command plus the replay check and counting. One thread
// calls verify(); counters() may be read from any thread.
class OperatorVerifier {
 public:
  // max_senders bounds the replay table. A full table evicts senders not
  // accepted for 2 * max_age (safe: anything they sent before is stale by
  // now) and otherwise refuses new senders with kTooManySenders.
  OperatorVerifier(OperatorKey key, CommandPolicy policy, std::size_t max_senders = 256);

  DecodedCommand verify(const void* data, std::size_t size, int64_t now_utime);
  // A signed claim that is not an operator command (the console's
  // take_control): the same checks of form, version, tag, staleness and
  // replay, in the same replay table (one sequence per sender whatever it
  // signs); its command must be `name` and its value 0. Refusals are counted
  // as verify()'s; an accepted claim is not counted (it queues nothing).
  DecodedCommand verify_claim(const operator_command_t& msg, std::string_view name, int64_t now_utime);
  // A refusal decided after verification (the console's not_in_control or
  // control_held, the receiver's queue_full): counted under `r` instead of
  // accepted when `was_accepted`, else simply counted.
  void count_refusal(RejectReason r, bool was_accepted) noexcept {
    if (was_accepted) counters_.move(RejectReason::kNone, r);
    else counters_.add(r);
  }

  const RejectCounters& counters() const { return counters_; }
  const OperatorKey& key() const { return key_; }
  const CommandPolicy& policy() const { return policy_; }

 private:
  struct SenderState {
    int64_t last_sequence = 0;
    int64_t last_accept_utime = 0;  // rig clock
  };
  bool make_room(int64_t now_utime);
  // The replay check and table update of an authentic, fresh message.
  void check_replay(DecodedCommand& d, int64_t now_utime);

  OperatorKey key_;
  CommandPolicy policy_;
  std::size_t max_senders_;
  std::unordered_map<std::string, SenderState> senders_;
  RejectCounters counters_;
};

}  // namespace rigctl
