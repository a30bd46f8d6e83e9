// Fuzzes the operator-command decoder, rt/comms/operator_auth.cpp: the bytes of
// one LCM operator_command_t from the network, which must be "pure and total:
// any bytes, any size, never throws or crashes; garbage gives kMalformed".
// Raw bytes alone stop at the HMAC check, so each input is used three ways:
//   1. as is: decode_operator_command() and decode_operator_ack();
//      (lcm_encode() throwing std::runtime_error for a string with an
//      embedded NUL, which LCM cannot carry, is expected);
//   2. as the fields of a command that the harness signs with the rig's key
//      (sign(), lcm_encode()), so staleness, names, values and limits are
//      reached; a well-formed signed command must get past the tag, and an
//      accepted one must respect the policy;
//   3. through OperatorVerifier twice (the second must be kReplayed) and from
//      a second sender with a one-sender table (kTooManySenders);
// and an ack built from the same fields must verify after an LCM round trip.
// Seeds: FUZZ_WRITE_SEEDS=DIR build-fuzz/fuzz_operator_command writes signed
// commands into DIR with the project's own encoder, then exits.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "tests/fuzz/fuzz_input.hpp"
#include "rt/comms/operator_auth.hpp"

using namespace rigctl;
using fuzz::check;

namespace {

constexpr int64_t kNow = 1'763'700'000'000'000;  // rig clock [us]

const OperatorKey& key() {
  static const OperatorKey k = [] {
    const std::string bytes(32, 'k');
    return OperatorKey::from_bytes(bytes.data(), bytes.size());
  }();
  return k;
}

CommandPolicy policy() {
  CommandPolicy p;
  p.max_age_us = 2'000'000;
  p.setpoint_min = -0.1;
  p.setpoint_max = 0.1;
  p.setpoint_unit = "m";
  return p;
}

std::string take_string(fuzz::Reader& in, std::size_t max) {
  const std::size_t n = in.u8() % (max + 1);
  std::string s;
  for (std::size_t i = 0; i < n && in.remaining() > 0; ++i) s.push_back(static_cast<char>(in.u8()));
  return s;
}

bool no_nul(const std::string& s) { return s.find('\0') == std::string::npos; }

void check_decoded(const DecodedCommand& d) {
  check(to_string(d.reason) != "unknown", "reason has a name");
  if (!d.ok()) {
    check(!d.detail.empty() || d.reason == RejectReason::kMalformed, "a rejection names its reason");
    return;
  }
  check(valid_sender_id(d.sender) && d.sequence > 0, "accepted: valid sender and sequence");
  check(std::abs(static_cast<long double>(kNow) - static_cast<long double>(d.utime)) <= 2'000'000, "accepted: fresh");
  if (d.command.kind == OperatorCommandKind::kSetpoint) {
    check(std::isfinite(d.command.value) && d.command.value >= -0.1 && d.command.value <= 0.1, "accepted setpoint in limits");
  } else {
    check(d.command.value == 0.0, "accepted command without a value");
  }
}

// The fields of a command from the input (front to back): flags u8 (bit 0
// version 2, bit 1 sequence <= 0, bits 2-3 utime scale), sequence u32, utime
// offset i32, value f64 (or, with bit 4, a small setpoint from a u8), sender
// (length u8 mod 81, bytes), command (length u8 mod 41, bytes; with bit 5 a
// known name picked by the length byte).
operator_command_t command_from(fuzz::Reader& in) {
  static const char* const kNames[] = {"arm", "start", "hold", "resume", "stop", "reset", "hydraulics_low",
                                       "hydraulics_high", "hydraulics_off", "setpoint", "stop_at_block_end"};
  operator_command_t msg{};
  const uint8_t flags = in.u8();
  msg.version = (flags & 1) ? 2 : kOperatorWireVersion;
  const uint32_t seq = in.u32();
  msg.sequence = (flags & 2) ? -static_cast<int64_t>(seq) : static_cast<int64_t>(seq) + 1;
  const auto offset = static_cast<int32_t>(in.u32());
  static const uint64_t kScale[] = {0, 1, 64, 1'000'000'000'000};
  // Wrapping arithmetic: with the largest scale any int64 utime is reachable.
  msg.utime = static_cast<int64_t>(static_cast<uint64_t>(kNow) +
                                   static_cast<uint64_t>(static_cast<int64_t>(offset)) * kScale[(flags >> 2) & 3]);
  msg.value = in.f64();
  if (flags & 0x10) msg.value = (static_cast<int>(in.u8()) - 128) * 0.001;
  msg.sender = take_string(in, 80);
  if (flags & 0x20) {
    msg.command = kNames[in.u8() % (sizeof kNames / sizeof kNames[0])];
  } else {
    msg.command = take_string(in, 40);
  }
  return msg;
}

void write_seeds(const char* dir) {
  struct Seed { const char* name; const char* sender; int64_t seq; int64_t dt; const char* cmd; double value; };
  const Seed seeds[] = {
      {"arm", "alice@rigpc", 1, 0, "arm", 0.0},          {"start", "alice@rigpc", 2, -1'500'000, "start", 0.0},
      {"setpoint", "bob", 7, 900'000, "setpoint", 0.05}, {"setpoint_out", "bob", 8, 0, "setpoint", 0.5},
      {"stale", "carol", 3, -5'000'000, "stop", 0.0},    {"unknown", "dave", 4, 0, "launch", 0.0},
      {"value", "erin", 5, 0, "hold", 1.0},              {"hydraulics", "op-1.x", 9, 10, "hydraulics_high", 0.0},
  };
  for (const Seed& s : seeds) {
    operator_command_t msg{};
    msg.version = kOperatorWireVersion;
    msg.sender = s.sender;
    msg.sequence = s.seq;
    msg.utime = kNow + s.dt;
    msg.command = s.cmd;
    msg.value = s.value;
    sign(msg, key());
    const std::vector<uint8_t> bytes = lcm_encode(msg);
    const std::string path = std::string(dir) + "/" + s.name;
    FILE* f = std::fopen(path.c_str(), "wb");
    check(f != nullptr, "open seed file");
    std::fwrite(bytes.data(), 1, bytes.size(), f);
    std::fclose(f);
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  if (const char* dir = std::getenv("FUZZ_WRITE_SEEDS")) {
    write_seeds(dir);
    std::exit(0);
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  // 1. The bytes as received.
  check_decoded(decode_operator_command(data, size, key(), policy(), kNow));
  operator_ack_t raw_ack{};
  (void)decode_operator_ack(data, size, raw_ack);

  // 2. The bytes as the fields of a signed command.
  fuzz::Reader in{data, size};
  operator_command_t msg = command_from(in);
  sign(msg, key());
  std::vector<uint8_t> wire;
  try {
    wire = lcm_encode(msg);
  } catch (const std::runtime_error&) {
    // lcm_encode refuses what LCM cannot carry: a string with an embedded NUL.
    check(!no_nul(msg.sender) || !no_nul(msg.command), "lcm_encode failed on a message without an embedded NUL");
    return 0;
  }
  const DecodedCommand d = decode_operator_command(wire.data(), wire.size(), key(), policy(), kNow);
  check_decoded(d);
  const bool well_formed = msg.version == kOperatorWireVersion && no_nul(msg.sender) && no_nul(msg.command) &&
                           valid_sender_id(msg.sender) && msg.command.size() <= kMaxCommandNameLength &&
                           msg.sequence > 0;
  if (well_formed) {
    check(d.reason != RejectReason::kMalformed && d.reason != RejectReason::kBadVersion &&
              d.reason != RejectReason::kBadTag,
          "a well-formed signed command gets past the tag");
    check(d.sender == msg.sender && d.sequence == msg.sequence && d.utime == msg.utime, "fields as sent");
  }

  // 3. Replay and the sender table.
  OperatorVerifier verifier(key(), policy(), 1);
  const DecodedCommand first = verifier.verify(wire.data(), wire.size(), kNow);
  const DecodedCommand again = verifier.verify(wire.data(), wire.size(), kNow);
  check(first.reason == d.reason, "verify agrees with decode");
  if (first.ok()) {
    check(again.reason == RejectReason::kReplayed, "the same command twice is a replay");
    operator_command_t other = msg;
    other.sender = msg.sender == "zz" ? "yy" : "zz";
    sign(other, key());
    const std::vector<uint8_t> w2 = lcm_encode(other);
    check(verifier.verify(w2.data(), w2.size(), kNow).reason == RejectReason::kTooManySenders,
          "a second sender with a one-sender table");
    check(verifier.counters().accepted() == 1 && verifier.counters().rejected() == 2, "counters");
  }

  // An ack with the same fields: signed, LCM round trip, verifies.
  operator_ack_t ack{};
  ack.version = kOperatorWireVersion;
  ack.utime = msg.utime;
  ack.sender = msg.sender;
  ack.sequence = msg.sequence;
  ack.accepted = d.ok();
  ack.reason = std::string(to_string(d.reason));
  ack.message = d.detail;
  sign(ack, key());
  check(tag_valid(ack, key()), "a signed ack verifies");
  const std::vector<uint8_t> ack_wire = lcm_encode(ack);  // no NUL here: the command encoded above
  operator_ack_t back{};
  const bool decoded = decode_operator_ack(ack_wire.data(), ack_wire.size(), back);
  if (no_nul(ack.sender) && no_nul(ack.message) && ack.sender.size() <= kMaxSenderLength && ack.message.size() <= 1024) {
    check(decoded && tag_valid(back, key()), "an ack survives the LCM round trip");
  }
  return 0;
}
