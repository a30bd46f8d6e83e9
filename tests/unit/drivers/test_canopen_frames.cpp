// CANopen frame encoding and decoding (drivers/canopen): the frame struct
// against the kernel's, COB-ID classification of the whole 11-bit space, NMT,
// heartbeat, EMCY and PDO codecs, and malformed frames of every kind, which
// must be classified, counted and never crash a decoder.
#include <gtest/gtest.h>
#include <linux/can.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "drivers/canopen/protocol/can_frame.hpp"
#include "drivers/canopen/protocol/cia408.hpp"
#include "drivers/canopen/protocol/cob_id.hpp"
#include "drivers/canopen/protocol/emcy.hpp"
#include "drivers/canopen/protocol/frame_stats.hpp"
#include "drivers/canopen/protocol/nmt.hpp"
#include "drivers/canopen/protocol/pdo.hpp"
#include "drivers/canopen/protocol/sdo.hpp"

using namespace rigctl::canopen;

namespace {

CanFrame frame(uint32_t can_id, std::initializer_list<uint8_t> bytes) {
  CanFrame f = make_frame(can_id, bytes);
  f.can_id = can_id;  // keep any flag bits the test sets
  return f;
}

}  // namespace

// ---------------------------------------------------------------- struct layout

TEST(CanFrameLayout, MatchesLinuxCanFrame) {
  EXPECT_EQ(sizeof(CanFrame), sizeof(struct can_frame));
  EXPECT_EQ(alignof(CanFrame), alignof(struct can_frame));
  EXPECT_EQ(offsetof(CanFrame, can_id), offsetof(struct can_frame, can_id));
  EXPECT_EQ(offsetof(CanFrame, len), offsetof(struct can_frame, can_dlc));
  EXPECT_EQ(offsetof(CanFrame, data), offsetof(struct can_frame, data));
  EXPECT_EQ(offsetof(CanFrame, len8_dlc), offsetof(struct can_frame, len8_dlc));
  EXPECT_EQ(kCanEffFlag, CAN_EFF_FLAG);
  EXPECT_EQ(kCanRtrFlag, CAN_RTR_FLAG);
  EXPECT_EQ(kCanErrFlag, CAN_ERR_FLAG);
  EXPECT_EQ(kCanSffMask, CAN_SFF_MASK);
  EXPECT_EQ(kCanEffMask, CAN_EFF_MASK);
  EXPECT_EQ(kCanMaxDataLen, CAN_MAX_DLEN);
}

TEST(CanFrameLayout, BytesRoundTripThroughKernelStruct) {
  struct can_frame k {};
  k.can_id = 0x181;
  k.can_dlc = 6;
  for (int i = 0; i < 8; ++i) k.data[i] = static_cast<uint8_t>(0xA0 + i);
  CanFrame f;
  std::memcpy(static_cast<void*>(&f), &k, sizeof f);
  EXPECT_EQ(f.can_id, 0x181U);
  EXPECT_EQ(f.len, 6);
  for (int i = 0; i < 8; ++i) EXPECT_EQ(f.data[i], 0xA0 + i);

  const CanFrame g = make_frame(0x605, {0x40, 0x00, 0x63, 0x01});
  struct can_frame k2 {};
  std::memcpy(&k2, &g, sizeof g);
  EXPECT_EQ(k2.can_id, 0x605U);
  EXPECT_EQ(k2.can_dlc, 4);
  EXPECT_EQ(k2.data[2], 0x63);
}

TEST(CanFrameLayout, MakeFrameAndLittleEndianHelpers) {
  const CanFrame f = make_frame(0x7FF, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10});
  EXPECT_EQ(f.len, 8);  // at most 8 bytes are taken
  EXPECT_EQ(f.data[7], 8);
  uint8_t b[4]{};
  put_u32le(b, 0x05040000);
  EXPECT_EQ(b[0], 0x00);
  EXPECT_EQ(b[2], 0x04);
  EXPECT_EQ(b[3], 0x05);
  EXPECT_EQ(get_u32le(b), 0x05040000U);
  put_u16le(b, 0x6300);
  EXPECT_EQ(b[0], 0x00);
  EXPECT_EQ(b[1], 0x63);
  EXPECT_EQ(get_u16le(b), 0x6300);
}

// ---------------------------------------------------------------- COB-IDs

TEST(CobId, EveryFunctionAtNodeEdges) {
  struct Case {
    uint32_t id;
    Function f;
    uint8_t node;
  };
  const Case cases[] = {
      {0x000, Function::kNmt, 0},       {0x080, Function::kSync, 0},       {0x100, Function::kTime, 0},
      {0x081, Function::kEmcy, 1},      {0x0FF, Function::kEmcy, 127},     {0x181, Function::kTpdo1, 1},
      {0x1FF, Function::kTpdo1, 127},   {0x281, Function::kTpdo2, 1},      {0x2FF, Function::kTpdo2, 127},
      {0x381, Function::kTpdo3, 1},     {0x3FF, Function::kTpdo3, 127},    {0x481, Function::kTpdo4, 1},
      {0x4FF, Function::kTpdo4, 127},   {0x201, Function::kRpdo1, 1},      {0x27F, Function::kRpdo1, 127},
      {0x301, Function::kRpdo2, 1},     {0x37F, Function::kRpdo2, 127},    {0x401, Function::kRpdo3, 1},
      {0x47F, Function::kRpdo3, 127},   {0x501, Function::kRpdo4, 1},      {0x57F, Function::kRpdo4, 127},
      {0x581, Function::kSdoTx, 1},     {0x5FF, Function::kSdoTx, 127},    {0x601, Function::kSdoRx, 1},
      {0x67F, Function::kSdoRx, 127},   {0x701, Function::kHeartbeat, 1},  {0x77F, Function::kHeartbeat, 127},
  };
  for (const auto& c : cases) {
    const CobInfo info = classify_cob_id(c.id);
    EXPECT_EQ(info.function, c.f) << std::hex << c.id;
    EXPECT_EQ(info.node, c.node) << std::hex << c.id;
    EXPECT_EQ(cob_id(c.f, c.node), c.id) << function_name(c.f);
    EXPECT_EQ(classify(make_frame(c.id, {})).function, c.f);
  }
}

TEST(CobId, UnusedIdsAreUnknown) {
  for (uint32_t id : {0x001U, 0x07FU, 0x101U, 0x17FU, 0x180U, 0x200U, 0x280U, 0x500U, 0x580U, 0x600U, 0x680U, 0x6FFU,
                      0x700U, 0x780U, 0x7E4U, 0x7E5U, 0x7FFU, 0x800U, 0x1FFFFFFFU}) {
    EXPECT_EQ(classify_cob_id(id).function, Function::kUnknown) << std::hex << id;
    if (id <= kCanSffMask) {
      CobInfo info;
      EXPECT_EQ(check_frame(make_frame(id, {}), info), Malformed::kUnknownCobId) << std::hex << id;
    }
  }
}

TEST(CobId, WholeElevenBitSpaceRoundTrips) {
  int known = 0;
  for (uint32_t id = 0; id <= kCanSffMask; ++id) {
    const CobInfo info = classify_cob_id(id);
    if (info.function == Function::kUnknown) continue;
    ++known;
    EXPECT_EQ(cob_id(info.function, info.node), id) << std::hex << id;
  }
  // NMT, SYNC, TIME + 127 nodes x (EMCY, 8 PDOs, 2 SDOs, heartbeat)
  EXPECT_EQ(known, 3 + 127 * 12);
}

TEST(CobId, BuildersRejectBadNodes) {
  EXPECT_EQ(cob_id(Function::kSdoRx, 0), 0xFFFFFFFFU);
  EXPECT_EQ(cob_id(Function::kSdoRx, 128), 0xFFFFFFFFU);
  EXPECT_EQ(cob_id(Function::kUnknown, 5), 0xFFFFFFFFU);
  EXPECT_EQ(cob_id(Function::kNmt, 99), 0x000U);
  EXPECT_EQ(cob_id(tpdo(3), 5), 0x385U);
  EXPECT_EQ(cob_id(rpdo(4), 5), 0x505U);
  EXPECT_EQ(tpdo(0), Function::kUnknown);
  EXPECT_EQ(rpdo(5), Function::kUnknown);
  EXPECT_EQ(pdo_number(Function::kRpdo2), 2);
  EXPECT_EQ(pdo_number(Function::kSdoTx), 0);
  EXPECT_TRUE(is_tpdo(Function::kTpdo4));
  EXPECT_FALSE(is_tpdo(Function::kRpdo4));
  EXPECT_TRUE(is_rpdo(Function::kRpdo1));
}

TEST(CobId, NonDataFramesAreNotCanopen) {
  CobInfo info;
  EXPECT_EQ(check_frame(frame(0x701 | kCanRtrFlag, {}), info), Malformed::kNotDataFrame);  // node guarding RTR
  EXPECT_EQ(check_frame(frame(0x181 | kCanEffFlag, {1, 2}), info), Malformed::kNotDataFrame);
  EXPECT_EQ(check_frame(frame(kCanErrFlag | 0x004, {0, 0, 0, 0, 0, 0, 0, 0}), info), Malformed::kNotDataFrame);
  EXPECT_EQ(classify(frame(0x181 | kCanEffFlag, {})).function, Function::kUnknown);
}

TEST(CobId, FixedLengthsPerService) {
  CobInfo info;
  EXPECT_EQ(check_frame(make_frame(0x000, {0x01, 0x05}), info), Malformed::kNone);
  EXPECT_EQ(check_frame(make_frame(0x000, {0x01}), info), Malformed::kWrongLength);
  EXPECT_EQ(check_frame(make_frame(0x080, {}), info), Malformed::kNone);
  EXPECT_EQ(check_frame(make_frame(0x080, {7}), info), Malformed::kNone);
  EXPECT_EQ(check_frame(make_frame(0x080, {7, 8}), info), Malformed::kWrongLength);
  EXPECT_EQ(check_frame(make_frame(0x085, {0, 0, 0, 0, 0, 0, 0}), info), Malformed::kWrongLength);
  EXPECT_EQ(check_frame(make_frame(0x585, {0x60, 0, 0x63, 1}), info), Malformed::kWrongLength);
  EXPECT_EQ(check_frame(make_frame(0x705, {}), info), Malformed::kWrongLength);
  EXPECT_EQ(check_frame(make_frame(0x185, {1, 2, 3}), info), Malformed::kNone);  // PDO: mapping decides
  CanFrame big = make_frame(0x185, {});
  big.len = 9;
  EXPECT_EQ(check_frame(big, info), Malformed::kWrongLength);
  EXPECT_EQ(info.function, Function::kTpdo1);
}

// ---------------------------------------------------------------- NMT

TEST(Nmt, EncodeCommands) {
  const std::pair<NmtCommand, uint8_t> cmds[] = {{NmtCommand::kStart, 0x01},
                                                 {NmtCommand::kStop, 0x02},
                                                 {NmtCommand::kEnterPreOperational, 0x80},
                                                 {NmtCommand::kResetNode, 0x81},
                                                 {NmtCommand::kResetCommunication, 0x82}};
  for (const auto& [cmd, byte] : cmds) {
    const CanFrame f = encode_nmt(cmd, 0x20);
    EXPECT_EQ(f.can_id, 0x000U);
    ASSERT_EQ(f.len, 2);
    EXPECT_EQ(f.data[0], byte) << nmt_command_name(cmd);
    EXPECT_EQ(f.data[1], 0x20);
    NmtMessage m;
    ASSERT_EQ(decode_nmt(f, m), Malformed::kNone);
    EXPECT_EQ(m.command, cmd);
    EXPECT_EQ(m.node, 0x20);
  }
  const CanFrame all = encode_nmt(NmtCommand::kStart, 0);
  EXPECT_EQ(all.data[1], 0);
}

TEST(Nmt, DecodeRejectsBadFrames) {
  NmtMessage m;
  EXPECT_EQ(decode_nmt(make_frame(0x000, {0x03, 0x01}), m), Malformed::kBadContent);
  EXPECT_EQ(decode_nmt(make_frame(0x000, {0x01, 0x80}), m), Malformed::kBadContent);
  EXPECT_EQ(decode_nmt(make_frame(0x000, {0x01}), m), Malformed::kWrongLength);
  EXPECT_EQ(decode_nmt(make_frame(0x000, {0x01, 0x01, 0x00}), m), Malformed::kWrongLength);
  EXPECT_EQ(decode_nmt(make_frame(0x080, {}), m), Malformed::kUnknownCobId);
}

// ---------------------------------------------------------------- heartbeat

TEST(HeartbeatFrame, EncodeAndDecodeEveryState) {
  const std::pair<NmtState, uint8_t> states[] = {{NmtState::kBootUp, 0x00},
                                                 {NmtState::kStopped, 0x04},
                                                 {NmtState::kOperational, 0x05},
                                                 {NmtState::kPreOperational, 0x7F}};
  for (uint8_t node : {uint8_t{1}, uint8_t{127}}) {
    for (const auto& [state, byte] : states) {
      const CanFrame f = encode_heartbeat(node, state);
      EXPECT_EQ(f.can_id, 0x700U + node);
      ASSERT_EQ(f.len, 1);
      EXPECT_EQ(f.data[0], byte);
      Heartbeat hb;
      ASSERT_EQ(decode_heartbeat(f, hb), Malformed::kNone);
      EXPECT_EQ(hb.node, node);
      EXPECT_EQ(hb.state, state) << nmt_state_name(state);
    }
  }
}

TEST(HeartbeatFrame, ToggleBitIgnoredAndBadFramesRejected) {
  Heartbeat hb;
  ASSERT_EQ(decode_heartbeat(make_frame(0x705, {0x85}), hb), Malformed::kNone);
  EXPECT_EQ(hb.state, NmtState::kOperational);
  EXPECT_EQ(decode_heartbeat(make_frame(0x705, {0x01}), hb), Malformed::kBadContent);
  EXPECT_EQ(decode_heartbeat(make_frame(0x705, {0x7E}), hb), Malformed::kBadContent);
  EXPECT_EQ(decode_heartbeat(make_frame(0x705, {}), hb), Malformed::kWrongLength);
  EXPECT_EQ(decode_heartbeat(make_frame(0x705, {0x05, 0x00}), hb), Malformed::kWrongLength);
  EXPECT_EQ(decode_heartbeat(make_frame(0x700, {0x05}), hb), Malformed::kUnknownCobId);
  EXPECT_EQ(decode_heartbeat(make_frame(0x185, {0x05}), hb), Malformed::kUnknownCobId);
  EXPECT_EQ(decode_heartbeat(frame(0x705 | kCanRtrFlag, {}), hb), Malformed::kNotDataFrame);
}

// ---------------------------------------------------------------- EMCY

TEST(Emcy, DecodeLayout) {
  Emcy e;
  ASSERT_EQ(decode_emcy(make_frame(0x08A, {0x30, 0x81, 0x11, 1, 2, 3, 4, 5}), e), Malformed::kNone);
  EXPECT_EQ(e.node, 10);
  EXPECT_EQ(e.error_code, 0x8130);
  EXPECT_EQ(e.error_register, error_register::kGeneric | error_register::kCommunication);
  EXPECT_EQ(e.manufacturer, (std::array<uint8_t, 5>{1, 2, 3, 4, 5}));
  EXPECT_FALSE(e.is_reset());
  EXPECT_STREQ(emcy_code_text(e.error_code), "life guard error or heartbeat error");

  ASSERT_EQ(decode_emcy(make_frame(0x0FF, {0, 0, 0, 0, 0, 0, 0, 0}), e), Malformed::kNone);
  EXPECT_EQ(e.node, 127);
  EXPECT_TRUE(e.is_reset());
}

TEST(Emcy, EncodeRoundTrip) {
  const Emcy e{1, 0x5000, error_register::kGeneric | error_register::kManufacturer, {0xDE, 0xAD, 0xBE, 0xEF, 0x01}};
  const CanFrame f = encode_emcy(e);
  EXPECT_EQ(f.can_id, 0x081U);
  EXPECT_EQ(f.len, 8);
  EXPECT_EQ(f.data[0], 0x00);
  EXPECT_EQ(f.data[1], 0x50);
  Emcy d;
  ASSERT_EQ(decode_emcy(f, d), Malformed::kNone);
  EXPECT_EQ(d, e);
}

TEST(Emcy, BadFrames) {
  Emcy e;
  EXPECT_EQ(decode_emcy(make_frame(0x081, {0, 0x10, 1, 0, 0, 0, 0}), e), Malformed::kWrongLength);
  EXPECT_EQ(decode_emcy(make_frame(0x081, {0, 0x10}), e), Malformed::kWrongLength);
  EXPECT_EQ(decode_emcy(make_frame(0x080, {}), e), Malformed::kUnknownCobId);  // that is SYNC
  EXPECT_EQ(decode_emcy(make_frame(0x701, {0, 0, 0, 0, 0, 0, 0, 0}), e), Malformed::kUnknownCobId);
}

TEST(Emcy, CodeTexts) {
  EXPECT_STREQ(emcy_code_text(0x0000), "error reset or no error");
  EXPECT_STREQ(emcy_code_text(0x0012), "error reset or no error");
  EXPECT_STREQ(emcy_code_text(0x1000), "generic error");
  EXPECT_STREQ(emcy_code_text(0x2310), "current");
  EXPECT_STREQ(emcy_code_text(0x2300), "current, device output side");
  EXPECT_STREQ(emcy_code_text(0x3210), "voltage");
  EXPECT_STREQ(emcy_code_text(0x4210), "temperature");
  EXPECT_STREQ(emcy_code_text(0x5000), "device hardware");
  EXPECT_STREQ(emcy_code_text(0x5530), "device hardware");
  EXPECT_STREQ(emcy_code_text(0x6101), "device software");
  EXPECT_STREQ(emcy_code_text(0x7000), "additional modules");
  EXPECT_STREQ(emcy_code_text(0x7510), "additional modules");
  EXPECT_STREQ(emcy_code_text(0x8110), "CAN overrun (objects lost)");
  EXPECT_STREQ(emcy_code_text(0x8120), "CAN in error passive mode");
  EXPECT_STREQ(emcy_code_text(0x8130), "life guard error or heartbeat error");
  EXPECT_STREQ(emcy_code_text(0x8140), "recovered from bus off");
  EXPECT_STREQ(emcy_code_text(0x8111), "communication");
  EXPECT_STREQ(emcy_code_text(0x8211), "protocol error");
  EXPECT_STREQ(emcy_code_text(0x8F00), "monitoring");
  EXPECT_STREQ(emcy_code_text(0x9000), "external error");
  EXPECT_STREQ(emcy_code_text(0xF000), "additional functions");
  EXPECT_STREQ(emcy_code_text(0xFF00), "device specific");
  EXPECT_STREQ(emcy_code_text(0xFF42), "device specific");
  EXPECT_STREQ(emcy_code_text(0xA000), "reserved");
  EXPECT_STREQ(emcy_code_text(0xF100), "reserved");
}

// ---------------------------------------------------------------- PDO

TEST(Pdo, RoundTripEveryType) {
  const PdoType types[] = {PdoType::kU8, PdoType::kI8, PdoType::kU16, PdoType::kI16, PdoType::kU32, PdoType::kI32};
  std::mt19937_64 rng(42);
  for (PdoType t : types) {
    PdoMapping m;
    ASSERT_TRUE(m.add({0x2000, 1, t, 1.0}));
    ASSERT_TRUE(m.add({0x2000, 2, t, 1.0}));
    EXPECT_EQ(m.byte_length(), 2 * pdo_type_bits(t) / 8);
    const int64_t lo = pdo_type_min(t), hi = pdo_type_max(t);
    std::uniform_int_distribution<int64_t> any(lo, hi);
    std::vector<std::array<int64_t, 2>> cases = {{lo, hi}, {0, 1}, {hi, lo}};
    if (pdo_type_signed(t)) cases.push_back({-1, -2});
    for (int i = 0; i < 200; ++i) cases.push_back({any(rng), any(rng)});
    for (const auto& v : cases) {
      CanFrame f;
      const auto r = encode_pdo_raw(m, 0x185, v, f);
      ASSERT_TRUE(r.ok);
      EXPECT_EQ(r.clamped, 0);
      EXPECT_EQ(f.can_id, 0x185U);
      EXPECT_EQ(f.len, m.byte_length());
      std::array<int64_t, 2> back{};
      ASSERT_EQ(decode_pdo_raw(m, f, back), Malformed::kNone);
      EXPECT_EQ(back, v) << "type bits " << int(pdo_type_bits(t));
    }
  }
}

TEST(Pdo, LittleEndianPacking) {
  PdoMapping m;
  ASSERT_TRUE(m.add({0x2001, 0, PdoType::kU8, 1.0}));
  ASSERT_TRUE(m.add({0x2002, 0, PdoType::kI8, 1.0}));
  ASSERT_TRUE(m.add({0x2003, 0, PdoType::kI16, 1.0}));
  ASSERT_TRUE(m.add({0x2004, 0, PdoType::kU32, 1.0}));
  EXPECT_EQ(m.byte_length(), 8);
  const std::array<int64_t, 4> v{0xAB, -3, -2, 0xDEADBEEF};
  CanFrame f;
  ASSERT_TRUE(encode_pdo_raw(m, 0x205, v, f).ok);
  const std::array<uint8_t, 8> want{0xAB, 0xFD, 0xFE, 0xFF, 0xEF, 0xBE, 0xAD, 0xDE};
  for (std::size_t i = 0; i < 8; ++i) EXPECT_EQ(f.data[i], want[i]) << i;
  EXPECT_FALSE(m.add({0x2005, 0, PdoType::kU8, 1.0}));  // would exceed 8 bytes
}

TEST(Pdo, MappingLimits) {
  PdoMapping m;
  for (int i = 0; i < 8; ++i) ASSERT_TRUE(m.add({0x2000, static_cast<uint8_t>(i), PdoType::kU8, 1.0}));
  EXPECT_FALSE(m.add({0x2000, 9, PdoType::kU8, 1.0}));
  EXPECT_EQ(m.size(), 8U);
  PdoMapping s;
  EXPECT_FALSE(s.add({0x2000, 1, PdoType::kI16, 0.0}));
  EXPECT_FALSE(s.add({0x2000, 1, PdoType::kI16, std::numeric_limits<double>::quiet_NaN()}));
  EXPECT_EQ(s.size(), 0U);
  EXPECT_EQ(pdo_mapping_value({cia408::kSplSetpoint, 1, PdoType::kI16, 1.0}), 0x63000110U);
  EXPECT_EQ(pdo_mapping_value({cia408::kControlWord, 0, PdoType::kU16, 1.0}), 0x60400010U);
  EXPECT_EQ(pdo_mapping_value({0x2000, 2, PdoType::kI32, 1.0}), 0x20000220U);
}

TEST(Pdo, Cia408SpoolScaling) {
  const PdoMapping rx = cia408::setpoint_mapping(false);
  ASSERT_EQ(rx.byte_length(), 4);
  CanFrame f;
  const std::array<double, 2> cmd{cia408::kControlActive, 0.5};
  auto r = encode_pdo(rx, 0x205, cmd, f);
  ASSERT_TRUE(r.ok);
  EXPECT_EQ(r.clamped, 0);
  EXPECT_EQ(get_u16le(&f.data[0]), 0x0007);
  EXPECT_EQ(static_cast<int16_t>(get_u16le(&f.data[2])), 8192);

  const std::array<double, 2> full_neg{cia408::kControlActive, -1.0};
  ASSERT_TRUE(encode_pdo(rx, 0x205, full_neg, f).ok);
  EXPECT_EQ(static_cast<int16_t>(get_u16le(&f.data[2])), -16384);

  const std::array<double, 2> too_far{cia408::kControlActive, 3.0};  // 300 % > INT16 range
  r = encode_pdo(rx, 0x205, too_far, f);
  EXPECT_EQ(r.clamped, 1);
  EXPECT_EQ(static_cast<int16_t>(get_u16le(&f.data[2])), 32767);
  const std::array<double, 2> nan{cia408::kControlActive, std::numeric_limits<double>::quiet_NaN()};
  r = encode_pdo(rx, 0x205, nan, f);
  EXPECT_EQ(r.clamped, 1);
  EXPECT_EQ(get_u16le(&f.data[2]), 0);  // NaN goes out as null, never as garbage
  const std::array<double, 1> short_values{0.0};
  EXPECT_FALSE(encode_pdo(rx, 0x205, short_values, f).ok);

  const PdoMapping tx = cia408::actual_mapping(true, cia408::kSpoolScale, 250e5 / cia408::kFullScale);
  ASSERT_EQ(tx.byte_length(), 6);
  const CanFrame in = make_frame(0x185, {0x0F, 0x00, 0x00, 0x40, 0x00, 0x20});  // ACTIVE, 16384, 8192
  std::array<double, 3> v{};
  ASSERT_EQ(decode_pdo(tx, in, v), Malformed::kNone);
  EXPECT_EQ(cia408::valve_state(static_cast<uint16_t>(v[0])), cia408::ValveState::kActive);
  EXPECT_DOUBLE_EQ(v[1], 1.0);
  EXPECT_DOUBLE_EQ(v[2], 125e5);
  EXPECT_EQ(cia408::valve_state(0x0B), cia408::ValveState::kHold);
  EXPECT_EQ(cia408::valve_state(0x03), cia408::ValveState::kFaultHold);
  EXPECT_EQ(cia408::valve_state(0x05), cia408::ValveState::kUndefined);
}

TEST(Pdo, WrongLengthIsMalformedAndLeavesOutputAlone) {
  const PdoMapping tx = cia408::actual_mapping(true);
  std::array<double, 3> v{7.0, 7.0, 7.0};
  EXPECT_EQ(decode_pdo(tx, make_frame(0x185, {1, 2, 3, 4, 5}), v), Malformed::kBadPdoLength);
  EXPECT_EQ(decode_pdo(tx, make_frame(0x185, {1, 2, 3, 4, 5, 6, 7}), v), Malformed::kBadPdoLength);
  EXPECT_EQ(decode_pdo(tx, make_frame(0x185, {}), v), Malformed::kBadPdoLength);
  EXPECT_EQ(decode_pdo(tx, frame(0x185 | kCanRtrFlag, {}), v), Malformed::kNotDataFrame);
  EXPECT_EQ(v, (std::array<double, 3>{7.0, 7.0, 7.0}));
}

// ---------------------------------------------------------------- stats

TEST(FrameStats, CountsByReason) {
  FrameStats s;
  s.count(Malformed::kNone);
  s.count(Malformed::kWrongLength);
  s.count(Malformed::kWrongLength);
  s.count(Malformed::kUnknownCobId);
  s.count(Malformed::kUnexpectedSdo);
  s.count(Malformed::kBadPdoLength);
  EXPECT_EQ(s.accepted, 1U);
  EXPECT_EQ(s[Malformed::kWrongLength], 2U);
  EXPECT_EQ(s[Malformed::kUnknownCobId], 1U);
  EXPECT_EQ(s[Malformed::kUnexpectedSdo], 1U);
  EXPECT_EQ(s[Malformed::kBadPdoLength], 1U);
  EXPECT_EQ(s.malformed(), 5U);
  EXPECT_STREQ(malformed_text(Malformed::kUnknownCobId), "unknown COB-ID");
}

// ---------------------------------------------------------------- fuzz

// Arbitrary frames through every decoder: nothing may crash (run the suite
// under ASan/UBSan to make "crash" include any out-of-bounds or UB), and what
// a decoder accepts must be consistent with the frame.
TEST(Fuzz, ArbitraryFramesThroughEveryDecoder) {
  std::mt19937_64 rng(20240601);
  std::uniform_int_distribution<uint32_t> u32;
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<int> pick(0, 9);

  const PdoMapping tx = cia408::actual_mapping(true);
  std::array<OdEntry, 3> od{{{0x6040, 0, 2, Access::kReadWrite, 0},
                             {0x6041, 0, 2, Access::kReadOnly, 0x0F},
                             {0x1017, 0, 2, Access::kReadWrite, 100}}};
  SdoServer server(5, od);
  SdoClient client(5, 1'000'000);
  HeartbeatConsumer consumer(5, 100'000'000);
  FrameStats stats;

  constexpr int kFrames = 200000;
  for (int i = 0; i < kFrames; ++i) {
    CanFrame f;
    // Bias towards the interesting ids of node 5 and node edges, but cover everything.
    switch (pick(rng)) {
      case 0: f.can_id = u32(rng); break;  // any flags, any id
      case 1: f.can_id = u32(rng) & kCanSffMask; break;
      case 2: f.can_id = 0x585; break;
      case 3: f.can_id = 0x605; break;
      case 4: f.can_id = 0x705; break;
      case 5: f.can_id = 0x085; break;
      case 6: f.can_id = 0x185; break;
      case 7: f.can_id = 0x000; break;
      case 8: f.can_id = (u32(rng) & 0xF) << 7 | (byte(rng) & 1 ? 0 : 127); break;
      default: f.can_id = (u32(rng) & 0xF) << 7 | 1; break;
    }
    f.len = static_cast<uint8_t>(byte(rng) < 200 ? byte(rng) % 9 : byte(rng));  // mostly 0..8, sometimes > 8
    for (auto& d : f.data) d = static_cast<uint8_t>(byte(rng));
    f.pad = static_cast<uint8_t>(byte(rng));
    f.res0 = static_cast<uint8_t>(byte(rng));
    f.len8_dlc = static_cast<uint8_t>(byte(rng));

    CobInfo info;
    const Malformed basic = check_frame(f, info);
    stats.count(basic);
    if (basic == Malformed::kNone) {
      ASSERT_TRUE(f.is_standard_data());
      ASSERT_LE(f.len, 8);
      ASSERT_NE(info.function, Function::kUnknown);
      ASSERT_EQ(cob_id(info.function, info.node), f.id());
    }

    NmtMessage nmt;
    if (decode_nmt(f, nmt) == Malformed::kNone) {
      ASSERT_EQ(f.can_id, 0U);
      ASSERT_EQ(f.len, 2);
      ASSERT_LE(nmt.node, 127);
    }
    Heartbeat hb;
    if (decode_heartbeat(f, hb) == Malformed::kNone) {
      ASSERT_EQ(f.can_id, 0x700U + hb.node);
      ASSERT_EQ(f.len, 1);
      consumer.on_heartbeat(hb, i * 1000);
    }
    consumer.poll(i * 1000);
    Emcy e;
    if (decode_emcy(f, e) == Malformed::kNone) {
      ASSERT_EQ(f.can_id, 0x080U + e.node);
      ASSERT_TRUE(valid_node_id(e.node));
      (void)emcy_code_text(e.error_code);
    }
    std::array<double, 3> pv{};
    const Malformed pm = decode_pdo(tx, f, pv);
    if (pm == Malformed::kNone) {
      ASSERT_EQ(f.len, tx.byte_length());
    }
    for (double x : pv) ASSERT_TRUE(std::isfinite(x));

    Malformed why = Malformed::kNone;
    const auto reply = server.on_frame(f, &why);
    if (reply) {
      ASSERT_EQ(reply->can_id, 0x585U);
      ASSERT_EQ(reply->len, 8);
      const uint8_t c = reply->data[0];
      ASSERT_TRUE(c == 0x60 || c == 0x80 || c == 0x4F || c == 0x4B || c == 0x47 || c == 0x43) << int(c);
    }

    if (!client.busy()) {
      if (i % 2) {
        client.start_upload(0x6041, 0, i * 1000);
      } else {
        client.start_download(0x6040, 0, 7, 2, i * 1000);
      }
    }
    const SdoResult r = client.on_frame(f, i * 1000);
    if (f.is_standard_data() && f.id() != 0x585) {
      ASSERT_EQ(r.kind, SdoResult::Kind::kIgnored);
    }
    if (r.kind == SdoResult::Kind::kAbort) {
      ASSERT_NE(r.text, nullptr);
    }
    if (r.kind == SdoResult::Kind::kDone) {
      ASSERT_LE(r.size, 4);
    }
    (void)client.poll(i * 1000);
  }
  EXPECT_EQ(stats.accepted + stats.malformed(), static_cast<uint64_t>(kFrames));
  EXPECT_GT(stats[Malformed::kNotDataFrame], 0U);
  EXPECT_GT(stats[Malformed::kUnknownCobId], 0U);
  EXPECT_GT(stats[Malformed::kWrongLength], 0U);
  EXPECT_GT(stats.accepted, 0U);
}
