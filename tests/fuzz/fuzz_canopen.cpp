// Fuzzes CAN frame decoding, drivers/canopen/: every decoder (COB-ID
// classification and length checks, EMCY, NMT, heartbeat, PDO with a fuzzed
// mapping, the SDO client and server state machines) gets every frame of the
// input. The decoders' contract (frame_stats.hpp): a bad frame is a Malformed
// reason, never a throw or a crash. Also checks their promises: a decoded
// frame re-encodes to the same bytes, answers are 8-byte frames on the
// right COB-ID, classification agrees with cob_id().
//
// Input, read from the front (tests/fuzz/make_seeds.py writes seeds in it):
// a 10-byte set-up: node id (may be 0 or > 127), PDO entry count (mod 10),
// two bytes of entry types, SDO timeout, heartbeat consumer time and
// producer period (u16 little-endian each, in 0.1 ms, minus 0.1 ms: -1 is
// "negative"); then frames of 14 bytes: can_id (u32 LE, flags included), len
// (may be > 8), 8 data bytes, an action byte (bits 0-3 time step, 4 start an
// SDO transfer, 5 upload/download, 5-7 download size and PDO span, 6 reset
// the heartbeat consumer).
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>

#include "tests/fuzz/fuzz_input.hpp"

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

using fuzz::check;

bool same_payload(const CanFrame& a, const CanFrame& b) {
  return a.id() == b.id() && a.len == b.len && a.len <= kCanMaxDataLen && std::memcmp(a.data, b.data, a.len) == 0;
}

void check_text(const char* s) { check(s != nullptr && std::strlen(s) < 200, "text"); }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  fuzz::Reader in{data, size};

  // ---- set-up
  const uint8_t node = in.u8();  // may be 0 or > 127 on purpose
  PdoMapping mapping;
  const uint8_t n_entries = static_cast<uint8_t>(in.u8() % 10);
  const uint8_t types = in.u8();
  const uint8_t types2 = in.u8();
  for (uint8_t i = 0; i < n_entries; ++i) {
    const unsigned t = ((i < 4 ? types : types2) >> (2 * (i % 4))) & 0x3;
    const bool sign = ((types ^ types2) >> i) & 1;
    const PdoType type = t == 0 ? (sign ? PdoType::kI8 : PdoType::kU8)
                         : t == 1 ? (sign ? PdoType::kI16 : PdoType::kU16)
                         : t == 2 ? (sign ? PdoType::kI32 : PdoType::kU32)
                                  : static_cast<PdoType>(6 + (types & 0x3));  // invalid type: add() must refuse
    const double scale = (i == 0 && (types & 0x80)) ? 0.0 : (i % 2 ? cia408::kSpoolScale : 1.0);
    const std::size_t before = mapping.size();
    const bool added = mapping.add({static_cast<uint16_t>(0x6000 + i), 1, type, scale});
    check(mapping.size() == before + (added ? 1 : 0), "mapping size");
    check(mapping.byte_length() <= 8, "mapping fits a frame");
  }
  const int64_t sdo_timeout = in.time_ns();
  const int64_t hb_consumer = in.time_ns();
  const int64_t hb_period = in.time_ns();

  SdoClient client(node, sdo_timeout);
  std::array<OdEntry, 6> od{{
      {cia408::kControlWord, 0, 2, Access::kReadWrite, 0},
      {cia408::kStatusWord, 0, 2, Access::kReadOnly, 0x0F},
      {cia408::kDeviceMode, 0, 1, Access::kReadWrite, 1},
      {cia408::kSplReferenceValue, 1, 2, Access::kReadOnly, 16384},
      {0x2000, 0, 4, Access::kWriteOnly, 0},
      {0x2001, 0, 7, Access::kReadWrite, 0},  // a bad entry size: answered with an abort
  }};
  SdoServer server(node, od);
  HeartbeatConsumer consumer(node, hb_consumer);
  HeartbeatProducer producer(node, hb_period);
  producer.start(0);
  FrameStats stats;
  int64_t now = 0;

  // ---- frames
  while (in.remaining() > 0) {
    CanFrame f;
    f.can_id = in.u32();
    f.len = in.u8();
    for (auto& b : f.data) b = in.u8();
    const uint8_t action = in.u8();
    now += static_cast<int64_t>(action & 0x0F) * 100'000'000 - 100'000'000;  // -0.1 .. +1.4 s, may go back

    // Classification.
    const CobInfo ci = classify(f);
    check_text(function_name(ci.function));
    if (ci.function != Function::kUnknown) {
      check(f.is_standard_data(), "classified a non-data frame");
      check(cob_id(ci.function, ci.node) == f.id(), "classify and cob_id disagree");
    }
    CobInfo info;
    const Malformed m = check_frame(f, info);
    stats.count(m);
    check_text(malformed_text(m));
    if (m == Malformed::kNone) check(f.len <= kCanMaxDataLen, "accepted a frame longer than 8 bytes");

    // EMCY.
    Emcy e;
    if (decode_emcy(f, e) == Malformed::kNone) {
      check(same_payload(encode_emcy(e), f), "EMCY re-encodes differently");
      check_text(emcy_code_text(e.error_code));
    }

    // NMT and heartbeat.
    NmtMessage nmt;
    if (decode_nmt(f, nmt) == Malformed::kNone) {
      check(same_payload(encode_nmt(nmt.command, nmt.node), f), "NMT re-encodes differently");
      check_text(nmt_command_name(nmt.command));
    }
    Heartbeat hb;
    if (decode_heartbeat(f, hb) == Malformed::kNone) {
      check(valid_node_id(hb.node), "heartbeat node id");
      check_text(nmt_state_name(hb.state));
      check_text(heartbeat_event_name(consumer.on_heartbeat(hb, now)));
    }
    check_text(heartbeat_event_name(consumer.poll(now)));
    if (action & 0x40) consumer.reset();
    if (const auto beat = producer.poll(now, NmtState::kOperational)) {
      check(beat->len == 1, "heartbeat length");
      check(producer.next_due_ns() > now, "heartbeat schedule moved past now");
    }

    // PDO.
    std::array<int64_t, PdoMapping::kMaxEntries> raw{};
    std::array<double, PdoMapping::kMaxEntries> eng{};
    const std::size_t take = action >> 5;  // out spans shorter than the mapping are allowed
    const Malformed pm = decode_pdo_raw(mapping, f, std::span<int64_t>(raw.data(), take));
    const Malformed pe = decode_pdo(mapping, f, std::span<double>(eng.data(), take));
    check(pm == pe, "decode_pdo and decode_pdo_raw disagree");
    if (pm == Malformed::kNone) {
      std::array<int64_t, PdoMapping::kMaxEntries> all{};
      (void)decode_pdo_raw(mapping, f, std::span<int64_t>(all.data(), mapping.size()));
      for (std::size_t i = 0; i < mapping.size(); ++i) {
        check(all[i] >= pdo_type_min(mapping[i].type) && all[i] <= pdo_type_max(mapping[i].type), "PDO value in range");
      }
      CanFrame again;
      const PdoEncodeResult r = encode_pdo_raw(mapping, f.can_id, std::span<const int64_t>(all.data(), mapping.size()), again);
      check(r.ok && r.clamped == 0 && same_payload(again, f), "PDO re-encodes differently");
      std::array<double, PdoMapping::kMaxEntries> values{};
      (void)decode_pdo(mapping, f, std::span<double>(values.data(), mapping.size()));
      const PdoEncodeResult r2 = encode_pdo(mapping, f.can_id, std::span<const double>(values.data(), mapping.size()), again);
      check(r2.ok && same_payload(again, f), "PDO engineering values re-encode differently");
    }

    // SDO client: start a transfer when asked, then feed the frame.
    if (action & 0x10) {
      const uint16_t index = get_u16le(&f.data[1]);
      if (action & 0x20) {
        (void)client.start_upload(index, f.data[3], now);
      } else {
        (void)client.start_download(index, f.data[3], get_u32le(&f.data[4]), static_cast<uint8_t>(action >> 5), now);
      }
    }
    const bool was_busy = client.busy();
    const SdoResult sr = client.on_frame(f, now);
    check_text(sdo_result_kind_name(sr.kind));
    check(sr.text != nullptr, "SDO result text");
    check_text(sr.text);
    if (sr.kind == SdoResult::Kind::kDone) {
      check(was_busy && !client.busy(), "SDO done without a transfer");
      check(sr.size <= 4, "SDO size");
    }
    if (sr.to_send) check(sr.to_send->len == 8 && sr.to_send->id() == client.request_cob_id(), "SDO abort frame");
    const SdoResult polled = client.poll(now);
    if (polled.to_send) check(polled.to_send->len == 8, "SDO timeout abort frame");
    if (action == 0xFF) client.cancel();

    // SDO server.
    Malformed why = Malformed::kNone;
    if (const auto answer = server.on_frame(f, &why)) {
      check(answer->len == 8 && answer->id() == kCobSdoTxBase + (node & 0x7F), "SDO server answer frame");
      check(why == Malformed::kNone, "answered a malformed request");
      if (answer->data[0] == sdo::kAbort) check_text(abort_code_text(get_u32le(&answer->data[4])));
    }
    check_text(malformed_text(why));
  }
    return 0;
}
