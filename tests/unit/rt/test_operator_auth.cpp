// Operator command authentication (rt/comms/operator_auth): HMAC-SHA256 and
// the canonical encoding against published and documented vectors, and the
// verifier accepting a valid command and rejecting and counting forged,
// replayed, stale and malformed ones under the right reason.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "operator_commands.hpp"
#include "rigctl/state_t.hpp"
#include "rt/comms/operator_auth.hpp"

using namespace rigctl;
using namespace rigctl::test;

namespace {

// ---------------------------------------------------------------- crypto and format

TEST(OperatorAuth, HmacSha256MatchesRfc4231TestCase6) {
  const std::vector<uint8_t> k(131, 0xaa);
  const std::string data = "Test Using Larger Than Block-Size Key - Hash Key First";
  const auto tag = hmac_sha256(OperatorKey::from_bytes(k.data(), k.size()), reinterpret_cast<const uint8_t*>(data.data()), data.size());
  EXPECT_EQ(hex(tag.data(), tag.size()), "60e431591ee0b67f0d8a26aacbf5b77f8e0bc6213728c5140546040f0ee37f54");
}

// The documented canonical encoding, byte for byte, and its tag (computed
// independently with Python's hmac; the same vector is in the docs).
TEST(OperatorAuth, CanonicalEncodingAndTagMatchTheDocumentedVector) {
  std::vector<uint8_t> kb(32);
  for (int i = 0; i < 32; ++i) kb[i] = static_cast<uint8_t>(i);
  const OperatorKey key = OperatorKey::from_bytes(kb.data(), kb.size());
  operator_command_t m = command("setpoint", 42, 0.01, 1'700'000'000'000'000);
  const auto canon = canonical_bytes(m);
  EXPECT_EQ(hex(canon.data(), canon.size()),
            "72696763746c2e6f70657261746f725f636f6d6d616e642e763100000000010000000b616c696365407269677063000000000000002a"
            "00060a24181e400000000008736574706f696e743f847ae147ae147b");
  sign(m, key);
  EXPECT_EQ(hex(m.tag, 32), "5346b1f0a62ff91f2d21aba62f9e9eed9d13b6ba6a939b321319de2fc82773fd");
}

TEST(OperatorAuth, AckRoundTripsAndItsTagCoversEveryField) {
  const OperatorKey key = key_of(7);
  operator_ack_t a;
  a.version = kOperatorWireVersion;
  a.utime = kNow;
  a.sender = "bob";
  a.sequence = 9;
  a.accepted = 0;
  a.reason = "stale";
  a.message = "field 'utime' is 3 s behind";
  sign(a, key);
  const auto bytes = lcm_encode(a);
  operator_ack_t b;
  ASSERT_TRUE(decode_operator_ack(bytes.data(), bytes.size(), b));
  EXPECT_EQ(b.reason, "stale");
  EXPECT_EQ(b.sequence, 9);
  EXPECT_TRUE(tag_valid(b, key));
  EXPECT_FALSE(tag_valid(b, key_of(8)));
  b.accepted = 1;  // a forger turning a rejection into an acceptance
  EXPECT_FALSE(tag_valid(b, key));
  EXPECT_FALSE(decode_operator_ack(bytes.data(), bytes.size() - 1, b));
  // A command's tag never verifies as an ack's: different labels.
  const auto cmd_bytes = signed_bytes(command("arm", 1), key);
  EXPECT_FALSE(decode_operator_ack(cmd_bytes.data(), cmd_bytes.size(), b));
}

// ---------------------------------------------------------------- verifier

TEST(OperatorVerifier, ValidCommandsAreAcceptedAndCounted) {
  const OperatorKey key = key_of(1);
  OperatorVerifier v(key, policy());
  const auto arm = signed_bytes(command("arm", 1), key);
  const DecodedCommand d = v.verify(arm.data(), arm.size(), kNow);
  ASSERT_TRUE(d.ok()) << to_string(d.reason) << ": " << d.detail;
  EXPECT_EQ(d.command.kind, OperatorCommandKind::kArm);
  EXPECT_EQ(d.command.sequence, 1u);
  EXPECT_EQ(d.sender, "alice@rigpc");

  const auto sp = signed_bytes(command("setpoint", 2, -0.03), key);
  const DecodedCommand s = v.verify(sp.data(), sp.size(), kNow + 1'500'000);  // 1.5 s old: inside the window
  ASSERT_TRUE(s.ok()) << s.detail;
  EXPECT_EQ(s.command.kind, OperatorCommandKind::kSetpoint);
  EXPECT_EQ(s.command.value, -0.03);

  for (auto [name, kind] : {std::pair{"hydraulics_low", OperatorCommandKind::kHydraulicsLow},
                            std::pair{"hydraulics_high", OperatorCommandKind::kHydraulicsHigh},
                            std::pair{"hydraulics_off", OperatorCommandKind::kHydraulicsOff},
                            std::pair{"start", OperatorCommandKind::kStart}, std::pair{"hold", OperatorCommandKind::kHold},
                            std::pair{"resume", OperatorCommandKind::kResume}, std::pair{"stop", OperatorCommandKind::kStop},
                            std::pair{"reset", OperatorCommandKind::kReset},
                            std::pair{"stop_at_block_end", OperatorCommandKind::kStopAtBlockEnd}}) {
    static int64_t seq = 10;
    const auto b = signed_bytes(command(name, ++seq), key);
    const DecodedCommand r = v.verify(b.data(), b.size(), kNow);
    EXPECT_TRUE(r.ok()) << name << ": " << r.detail;
    EXPECT_EQ(r.command.kind, kind) << name;
  }
  EXPECT_EQ(v.counters().accepted(), 11u);
  EXPECT_EQ(v.counters().rejected(), 0u);
}

TEST(OperatorVerifier, ForgedCommandsAreRejectedAsBadTag) {
  const OperatorKey key = key_of(1);
  OperatorVerifier v(key, policy());
  // Signed with another key.
  const auto other = signed_bytes(command("arm", 100), key_of(2));
  EXPECT_EQ(v.verify(other.data(), other.size(), kNow).reason, RejectReason::kBadTag);
  // One bit of the tag flipped (the tag is the last 32 bytes).
  auto flipped = signed_bytes(command("arm", 101), key);
  flipped[flipped.size() - 7] ^= 0x10;
  EXPECT_EQ(v.verify(flipped.data(), flipped.size(), kNow).reason, RejectReason::kBadTag);
  // The value changed after signing (setpoint 0.01 -> 0.04, still within limits).
  operator_command_t m = command("setpoint", 102, 0.01);
  sign(m, key);
  m.value = 0.04;
  const auto changed = lcm_encode(m);
  const DecodedCommand d = v.verify(changed.data(), changed.size(), kNow);
  EXPECT_EQ(d.reason, RejectReason::kBadTag);
  EXPECT_NE(d.detail.find("tag"), std::string::npos) << d.detail;
  // A forged sequence 102 did not raise alice's replay floor: her real 5 passes.
  const auto real = signed_bytes(command("arm", 5), key);
  EXPECT_TRUE(v.verify(real.data(), real.size(), kNow).ok());
  EXPECT_EQ(v.counters().get(RejectReason::kBadTag), 3u);
  EXPECT_EQ(v.counters().accepted(), 1u);
}

TEST(OperatorVerifier, EverySingleBitFlipOfAValidMessageIsRejected) {
  const OperatorKey key = key_of(1);
  const auto good = signed_bytes(command("setpoint", 7, 0.02), key);
  ASSERT_TRUE(decode_operator_command(good.data(), good.size(), key, policy(), kNow).ok());
  int flips = 0;
  for (std::size_t byte = 0; byte < good.size(); ++byte) {
    for (int bit = 0; bit < 8; ++bit) {
      auto b = good;
      b[byte] ^= static_cast<uint8_t>(1u << bit);
      const DecodedCommand d = decode_operator_command(b.data(), b.size(), key, policy(), kNow);
      EXPECT_FALSE(d.ok()) << "flip of byte " << byte << " bit " << bit << " accepted";
      ++flips;
    }
  }
  EXPECT_EQ(flips, static_cast<int>(good.size() * 8));
}

TEST(OperatorVerifier, ReplayedSequencesAreRejected) {
  const OperatorKey key = key_of(1);
  OperatorVerifier v(key, policy());
  const auto first = signed_bytes(command("start", 50), key);
  ASSERT_TRUE(v.verify(first.data(), first.size(), kNow).ok());
  // The very same bytes again.
  const DecodedCommand again = v.verify(first.data(), first.size(), kNow + 10'000);
  EXPECT_EQ(again.reason, RejectReason::kReplayed);
  EXPECT_NE(again.detail.find("50"), std::string::npos) << again.detail;
  // A lower sequence, properly signed.
  const auto lower = signed_bytes(command("stop", 49), key);
  EXPECT_EQ(v.verify(lower.data(), lower.size(), kNow).reason, RejectReason::kReplayed);
  // Sequences are per sender: bob's 50 is new.
  const auto bob = signed_bytes(command("stop", 50, 0.0, kNow, "bob"), key);
  EXPECT_TRUE(v.verify(bob.data(), bob.size(), kNow).ok());
  // Higher: accepted.
  const auto next = signed_bytes(command("stop", 51), key);
  EXPECT_TRUE(v.verify(next.data(), next.size(), kNow).ok());
  EXPECT_EQ(v.counters().get(RejectReason::kReplayed), 2u);
  EXPECT_EQ(v.counters().accepted(), 3u);
}

TEST(OperatorVerifier, StaleOrFutureCommandsAreRejected) {
  const OperatorKey key = key_of(1);
  OperatorVerifier v(key, policy());
  const auto old = signed_bytes(command("arm", 1, 0.0, kNow - 2'500'000), key);
  const DecodedCommand d = v.verify(old.data(), old.size(), kNow);
  EXPECT_EQ(d.reason, RejectReason::kStale);
  EXPECT_NE(d.detail.find("utime"), std::string::npos) << d.detail;
  const auto future = signed_bytes(command("arm", 2, 0.0, kNow + 2'500'000), key);
  EXPECT_EQ(v.verify(future.data(), future.size(), kNow).reason, RejectReason::kStale);
  // Extreme utimes must not overflow the age computation into "fresh".
  const auto min = signed_bytes(command("arm", 3, 0.0, std::numeric_limits<int64_t>::min()), key);
  EXPECT_EQ(v.verify(min.data(), min.size(), kNow).reason, RejectReason::kStale);
  const auto max = signed_bytes(command("arm", 4, 0.0, std::numeric_limits<int64_t>::max()), key);
  EXPECT_EQ(v.verify(max.data(), max.size(), kNow).reason, RejectReason::kStale);
  EXPECT_EQ(v.counters().get(RejectReason::kStale), 4u);
  EXPECT_EQ(v.counters().accepted(), 0u);
}

// Why the window matters besides sequence numbers: a restarted controller
// has an empty replay table.
TEST(OperatorVerifier, AfterARestartOnlyTheWindowStopsAReplay) {
  const OperatorKey key = key_of(1);
  const auto captured = signed_bytes(command("start", 77), key);
  {
    OperatorVerifier before(key, policy());
    ASSERT_TRUE(before.verify(captured.data(), captured.size(), kNow).ok());
  }
  OperatorVerifier restarted(key, policy());  // empty sequence table
  EXPECT_EQ(restarted.verify(captured.data(), captured.size(), kNow + 60'000'000).reason, RejectReason::kStale);
}

// Within the window too, once the verifier knows when it started: nothing
// signed before the start is taken (the receiver sets it to its own start).
TEST(OperatorVerifier, CommandsSignedBeforeTheStartAreRefused) {
  const OperatorKey key = key_of(1);
  CommandPolicy p = policy();
  p.not_before_utime = kNow - 100'000;  // restarted 0.1 s ago
  OperatorVerifier restarted(key, p);
  const auto captured = signed_bytes(command("start", 77, 0.0, kNow - 700'000), key);  // signed 0.7 s ago
  const DecodedCommand d = restarted.verify(captured.data(), captured.size(), kNow);
  EXPECT_EQ(d.reason, RejectReason::kStale);
  EXPECT_NE(d.detail.find("before this rig's command receiver started"), std::string::npos) << d.detail;
  const auto fresh = signed_bytes(command("start", 78, 0.0, kNow - 50'000), key);
  EXPECT_TRUE(restarted.verify(fresh.data(), fresh.size(), kNow).ok());
}

// A claim (the console's take_control) goes through the same checks and
// the same replay table as commands; its refusals are counted.
TEST(OperatorVerifier, AClaimIsCheckedLikeACommandInTheSameReplayTable) {
  const OperatorKey key = key_of(1);
  OperatorVerifier v(key, policy());
  auto claim = [&](int64_t seq, const OperatorKey& k, int64_t utime = kNow, const char* name = "take_control") {
    auto m = command(name, seq, 0.0, utime);
    sign(m, k);
    return v.verify_claim(m, "take_control", kNow);
  };
  EXPECT_EQ(claim(10, key_of(2)).reason, RejectReason::kBadTag);
  EXPECT_EQ(claim(10, key, kNow - 3'000'000).reason, RejectReason::kStale);
  EXPECT_EQ(claim(10, key, kNow, "hold").reason, RejectReason::kMalformed);  // a command is no claim
  EXPECT_TRUE(claim(10, key).ok());
  EXPECT_EQ(claim(10, key).reason, RejectReason::kReplayed);
  const auto cmd = signed_bytes(command("hold", 10), key);  // the claim used sequence 10 of this sender
  EXPECT_EQ(v.verify(cmd.data(), cmd.size(), kNow).reason, RejectReason::kReplayed);
  EXPECT_EQ(v.counters().get(RejectReason::kReplayed), 2u);
  EXPECT_EQ(v.counters().rejected(), 5u);
  EXPECT_EQ(v.counters().accepted(), 0u);  // an accepted claim queues nothing
}

TEST(OperatorAuth, TagsAreReadFromHexByOneDecoder) {
  uint8_t tag[kOperatorTagBytes];
  const std::string hex64 = "5346b1f0a62ff91f2d21aba62f9e9eed9d13b6ba6a939b321319de2fc82773fd";
  ASSERT_TRUE(tag_from_hex(hex64, tag));
  EXPECT_EQ(tag[0], 0x53);
  EXPECT_EQ(tag[31], 0xfd);
  EXPECT_TRUE(tag_from_hex("5346B1F0A62FF91F2D21ABA62F9E9EED9D13B6BA6A939B321319DE2FC82773FD", tag));
  EXPECT_FALSE(tag_from_hex(hex64.substr(2), tag));
  EXPECT_FALSE(tag_from_hex(hex64 + "00", tag));
  EXPECT_FALSE(tag_from_hex("zz" + hex64.substr(2), tag));
  EXPECT_FALSE(tag_from_hex(std::string("53\0") + hex64.substr(3), tag));
  EXPECT_FALSE(tag_from_hex("53:46" + hex64.substr(5), tag));
}

TEST(OperatorVerifier, MalformedMessagesAreRejectedAsMalformed) {
  const OperatorKey key = key_of(1);
  OperatorVerifier v(key, policy());
  const auto good = signed_bytes(command("arm", 1), key);
  uint64_t expected = 0;
  // Every truncation, including the empty message.
  for (std::size_t n = 0; n < good.size(); ++n) {
    EXPECT_EQ(v.verify(good.data(), n, kNow).reason, RejectReason::kMalformed) << "truncated to " << n << " bytes";
    ++expected;
  }
  EXPECT_EQ(v.verify(nullptr, 0, kNow).reason, RejectReason::kMalformed);
  ++expected;
  // A trailing byte.
  auto longer = good;
  longer.push_back(0);
  EXPECT_EQ(v.verify(longer.data(), longer.size(), kNow).reason, RejectReason::kMalformed);
  ++expected;
  // Another LCM type on the channel.
  state_t st;
  st.utime = kNow;
  st.tick = 1;
  st.t = 0;
  st.state = "running";
  std::vector<uint8_t> sb(static_cast<std::size_t>(st.getEncodedSize()));
  ASSERT_EQ(st.encode(sb.data(), 0, static_cast<int>(sb.size())), static_cast<int>(sb.size()));
  const DecodedCommand other = v.verify(sb.data(), sb.size(), kNow);
  EXPECT_EQ(other.reason, RejectReason::kMalformed);
  EXPECT_NE(other.detail.find("fingerprint"), std::string::npos) << other.detail;
  ++expected;
  // Sender id with a character outside the alphabet, and sequence 0 (both signed).
  const auto bad_sender = signed_bytes(command("arm", 1, 0.0, kNow, "alice\nFAKE LOG LINE"), key);
  EXPECT_EQ(v.verify(bad_sender.data(), bad_sender.size(), kNow).reason, RejectReason::kMalformed);
  const auto seq0 = signed_bytes(command("arm", 0), key);
  EXPECT_EQ(v.verify(seq0.data(), seq0.size(), kNow).reason, RejectReason::kMalformed);
  expected += 2;
  EXPECT_EQ(v.counters().get(RejectReason::kMalformed), expected);
  EXPECT_EQ(v.counters().rejected(), expected);
}

TEST(OperatorVerifier, WrongVersionUnknownCommandAndBadValuesAreRejected) {
  const OperatorKey key = key_of(1);
  OperatorVerifier v(key, policy());
  operator_command_t v2 = command("arm", 1);
  v2.version = 2;
  const auto b_v2 = signed_bytes(v2, key);
  EXPECT_EQ(v.verify(b_v2.data(), b_v2.size(), kNow).reason, RejectReason::kBadVersion);

  const auto launch = signed_bytes(command("launch", 2), key);
  const DecodedCommand u = v.verify(launch.data(), launch.size(), kNow);
  EXPECT_EQ(u.reason, RejectReason::kUnknownCommand);
  EXPECT_NE(u.detail.find("launch"), std::string::npos) << u.detail;
  const auto hyphen = signed_bytes(command("hydraulics-low", 3), key);  // the CLI's spelling is not the wire's
  EXPECT_EQ(v.verify(hyphen.data(), hyphen.size(), kNow).reason, RejectReason::kUnknownCommand);

  const auto nan = signed_bytes(command("setpoint", 4, std::numeric_limits<double>::quiet_NaN()), key);
  const DecodedCommand n = v.verify(nan.data(), nan.size(), kNow);
  EXPECT_EQ(n.reason, RejectReason::kBadValue);
  EXPECT_NE(n.detail.find("value"), std::string::npos) << n.detail;
  const auto inf = signed_bytes(command("setpoint", 5, std::numeric_limits<double>::infinity()), key);
  EXPECT_EQ(v.verify(inf.data(), inf.size(), kNow).reason, RejectReason::kBadValue);
  const auto arm_value = signed_bytes(command("arm", 6, 1.0), key);
  EXPECT_EQ(v.verify(arm_value.data(), arm_value.size(), kNow).reason, RejectReason::kBadValue);

  const auto high = signed_bytes(command("setpoint", 7, 0.0501), key);
  const DecodedCommand h = v.verify(high.data(), high.size(), kNow);
  EXPECT_EQ(h.reason, RejectReason::kOutOfLimits);
  EXPECT_NE(h.detail.find("0.0501 m outside [-0.05, 0.05]"), std::string::npos) << h.detail;
  const auto low = signed_bytes(command("setpoint", 8, -1.0), key);
  EXPECT_EQ(v.verify(low.data(), low.size(), kNow).reason, RejectReason::kOutOfLimits);
  // A rig without configured limits refuses every setpoint.
  OperatorVerifier unlimited(key, CommandPolicy{});
  const auto zero = signed_bytes(command("setpoint", 9, 0.0), key);
  EXPECT_EQ(unlimited.verify(zero.data(), zero.size(), kNow).reason, RejectReason::kOutOfLimits);

  EXPECT_EQ(v.counters().get(RejectReason::kBadVersion), 1u);
  EXPECT_EQ(v.counters().get(RejectReason::kUnknownCommand), 2u);
  EXPECT_EQ(v.counters().get(RejectReason::kBadValue), 3u);
  EXPECT_EQ(v.counters().get(RejectReason::kOutOfLimits), 2u);
  EXPECT_EQ(v.counters().accepted(), 0u);
  // Rejected commands do not use up a sequence: 1 is still free.
  const auto ok = signed_bytes(command("arm", 1), key);
  EXPECT_TRUE(v.verify(ok.data(), ok.size(), kNow).ok());
}

TEST(OperatorVerifier, ReplayTableIsBoundedAndEvictsOnlyIdleSenders) {
  const OperatorKey key = key_of(1);
  OperatorVerifier v(key, policy(), 2);
  const auto a = signed_bytes(command("arm", 1, 0.0, kNow, "a"), key);
  const auto b = signed_bytes(command("arm", 1, 0.0, kNow, "b"), key);
  const auto c = signed_bytes(command("arm", 1, 0.0, kNow, "c"), key);
  ASSERT_TRUE(v.verify(a.data(), a.size(), kNow).ok());
  ASSERT_TRUE(v.verify(b.data(), b.size(), kNow).ok());
  EXPECT_EQ(v.verify(c.data(), c.size(), kNow).reason, RejectReason::kTooManySenders);
  // 4.1 s later a and b are idle for more than twice the window: c gets a slot.
  const int64_t later = kNow + 4'100'000;
  const auto c2 = signed_bytes(command("arm", 2, 0.0, later, "c"), key);
  EXPECT_TRUE(v.verify(c2.data(), c2.size(), later).ok());
  // a's old message cannot come back through the eviction: it is stale.
  EXPECT_EQ(v.verify(a.data(), a.size(), later).reason, RejectReason::kStale);
}

TEST(OperatorVerifier, RandomGarbageIsRejectedWithoutCrashing) {
  const OperatorKey key = key_of(1);
  const auto good = signed_bytes(command("setpoint", 3, 0.01), key);
  std::mt19937 rng(12345);
  int accepted = 0;
  for (int i = 0; i < 20000; ++i) {
    std::vector<uint8_t> b;
    if (i % 2 == 0) {
      b.resize(rng() % 200);
      for (auto& x : b) x = static_cast<uint8_t>(rng());
      if (b.size() >= 8 && i % 4 == 0) std::memcpy(b.data(), good.data(), 8);  // right fingerprint, garbage after
    } else {
      b = good;  // a valid message with random bytes overwritten
      for (int k = 0; k < 1 + static_cast<int>(rng() % 4); ++k) b[rng() % b.size()] = static_cast<uint8_t>(rng());
      if (b == good) continue;
    }
    if (decode_operator_command(b.data(), b.size(), key, policy(), kNow).ok()) ++accepted;
  }
  EXPECT_EQ(accepted, 0);
}

}  // namespace
