// SDO transfers (CiA 301), client and server, as state machines driven by
// the caller: frames in, frames out, times passed in. No I/O, no clock, no
// allocation. Downloads are expedited (objects of 1..4 bytes); uploads are
// expedited or segmented, whichever the server chooses: CiA 301 lets a
// server answer any upload segmented, so a client must take both.
//
// Every SDO frame is 8 bytes: [command, index lo, index hi, subindex, d0..d3].
//   download request (client -> server, 0x600+node):
//     0x2F/0x2B/0x27/0x23 = 1/2/3/4 data bytes, size indicated; 0x22 = size not indicated
//   download response (0x580+node): 0x60
//   upload request: 0x40
//   upload response: 0x4F/0x4B/0x47/0x43 = 1/2/3/4 bytes; 0x42 = size not indicated
//   upload response, segmented: 0x41 (d0..d3 = size in bytes) or 0x40 (size not indicated)
//     then per segment: request 0x60 / 0x70 (toggle bit 4 alternating from 0),
//     response [0b000t nnnc, 7 data bytes]: t echoes the toggle, n = bytes of
//     the 7 not holding data, c = 1 on the last segment
//   abort (either way): 0x80, d0..d3 = 32-bit abort code, little-endian
// Segmented downloads and block transfers are not used: a server answers
// them with abort 0x05040001.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>

#include "drivers/canopen/protocol/can_frame.hpp"
#include "drivers/canopen/protocol/frame_stats.hpp"

namespace rigctl::canopen {

namespace sdo {
inline constexpr uint8_t kDownload1 = 0x2F;
inline constexpr uint8_t kDownload2 = 0x2B;
inline constexpr uint8_t kDownload3 = 0x27;
inline constexpr uint8_t kDownload4 = 0x23;
inline constexpr uint8_t kDownloadNoSize = 0x22;
inline constexpr uint8_t kDownloadResponse = 0x60;
inline constexpr uint8_t kUploadRequest = 0x40;
inline constexpr uint8_t kUpload1 = 0x4F;
inline constexpr uint8_t kUpload2 = 0x4B;
inline constexpr uint8_t kUpload3 = 0x47;
inline constexpr uint8_t kUpload4 = 0x43;
inline constexpr uint8_t kUploadNoSize = 0x42;
inline constexpr uint8_t kUploadSegmented = 0x40;      // initiate response, size not indicated
inline constexpr uint8_t kUploadSegmentedSize = 0x41;  // initiate response, d0..d3 = size
inline constexpr uint8_t kUploadSegmentRequest = 0x60; // | 0x10 with the toggle bit
inline constexpr uint8_t kToggleBit = 0x10;
inline constexpr uint8_t kAbort = 0x80;

// Standard abort codes (CiA 301).
inline constexpr uint32_t kAbortToggleBit = 0x05030000;
inline constexpr uint32_t kAbortTimeout = 0x05040000;
inline constexpr uint32_t kAbortCommand = 0x05040001;
inline constexpr uint32_t kAbortBlockSize = 0x05040002;
inline constexpr uint32_t kAbortSequence = 0x05040003;
inline constexpr uint32_t kAbortCrc = 0x05040004;
inline constexpr uint32_t kAbortOutOfMemory = 0x05040005;
inline constexpr uint32_t kAbortUnsupportedAccess = 0x06010000;
inline constexpr uint32_t kAbortWriteOnly = 0x06010001;   // attempt to read a write-only object
inline constexpr uint32_t kAbortReadOnly = 0x06010002;    // attempt to write a read-only object
inline constexpr uint32_t kAbortNoObject = 0x06020000;
inline constexpr uint32_t kAbortNotMappable = 0x06040041;
inline constexpr uint32_t kAbortPdoLength = 0x06040042;
inline constexpr uint32_t kAbortParameterIncompatible = 0x06040043;
inline constexpr uint32_t kAbortInternalIncompatible = 0x06040047;
inline constexpr uint32_t kAbortHardware = 0x06060000;
inline constexpr uint32_t kAbortLengthMismatch = 0x06070010;
inline constexpr uint32_t kAbortLengthTooHigh = 0x06070012;
inline constexpr uint32_t kAbortLengthTooLow = 0x06070013;
inline constexpr uint32_t kAbortNoSubindex = 0x06090011;
inline constexpr uint32_t kAbortInvalidValue = 0x06090030;
inline constexpr uint32_t kAbortValueTooHigh = 0x06090031;
inline constexpr uint32_t kAbortValueTooLow = 0x06090032;
inline constexpr uint32_t kAbortMaxLessThanMin = 0x06090036;
inline constexpr uint32_t kAbortResourceNotAvailable = 0x060A0023;
inline constexpr uint32_t kAbortGeneral = 0x08000000;
inline constexpr uint32_t kAbortCannotStore = 0x08000020;
inline constexpr uint32_t kAbortLocalControl = 0x08000021;
inline constexpr uint32_t kAbortDeviceState = 0x08000022;
inline constexpr uint32_t kAbortNoDictionary = 0x08000023;
inline constexpr uint32_t kAbortNoData = 0x08000024;
}  // namespace sdo

// Human-readable text of a standard abort code; "unknown abort code" otherwise.
const char* abort_code_text(uint32_t code);

// Mask of the low `size` bytes (0 or >= 4: all 32 bits).
constexpr uint32_t sdo_size_mask(uint8_t size) {
  return size == 0 || size >= 4 ? 0xFFFFFFFFU : (1U << (8U * size)) - 1U;
}

// The longest upload a client takes (a segmented upload beyond it is
// aborted with 0x05040005, out of memory): the objects a valve client reads
// are numbers of 1..4 bytes and short strings.
inline constexpr std::size_t kSdoMaxUpload = 64;

// Any 8-byte SDO frame: [command, index, subindex, 4 data bytes].
CanFrame sdo_frame(uint32_t cob_id, uint8_t command, uint16_t index, uint8_t subindex, uint32_t data);

// Builds request/response frames (also used by tests to forge bad ones).
CanFrame sdo_download_request(uint8_t node, uint16_t index, uint8_t subindex, uint32_t value, uint8_t size);
CanFrame sdo_upload_request(uint8_t node, uint16_t index, uint8_t subindex);
CanFrame sdo_abort(uint32_t cob_id, uint16_t index, uint8_t subindex, uint32_t code);

// Sign-extends the low `size` bytes (1..4) of an uploaded value.
constexpr int32_t sdo_sign_extend(uint32_t value, uint8_t size) {
  if (size == 0 || size >= 4) return static_cast<int32_t>(value);
  const unsigned shift = 32U - 8U * size;
  return static_cast<int32_t>(value << shift) >> shift;
}

struct SdoResult {
  enum class Kind : uint8_t {
    kPending,        // nothing finished (poll before the deadline, or no transfer)
    kDone,           // transfer confirmed; for an upload, value/size hold the data
    kAbort,          // aborted, by the server (its code) or by us on timeout (0x05040000)
    kProtocolError,  // the server answered with something that is not a valid answer; we abort it
    kIgnored,        // not a frame of this client (other COB-ID): nothing happened
    kMalformed,      // a frame of this client's channel that was dropped (see `malformed`)
  };
  Kind kind = Kind::kPending;
  uint16_t index = 0;  // of the transfer
  uint8_t subindex = 0;
  uint32_t value = 0;  // upload: the first (up to) 4 bytes, little-endian, zero-extended
  uint8_t size = 0;    // upload: bytes received (expedited 1..4, 0 when the server did not indicate it)
  bool segmented = false;  // upload: the server answered with a segmented transfer
  std::array<uint8_t, kSdoMaxUpload> bytes{};  // upload: the data, `size` bytes (4 for an unsized expedited one)
  uint32_t abort_code = 0;
  const char* text = "";  // abort code text or protocol error reason; static storage
  Malformed malformed = Malformed::kNone;
  // To send now: kAbort on timeout and kProtocolError, an abort frame for
  // the server; kPending during a segmented upload, the next segment request.
  std::optional<CanFrame> to_send;
};

// One transfer at a time with the server `node`. A response is in time if it
// arrives no later than the request + timeout (each segment of a segmented
// upload has its own timeout); a transfer still pending after that ends with
// abort 0x05040000, at poll() or at the next on_frame() (the late frame is
// then dropped). A segment whose toggle bit does not alternate ends the
// transfer with abort 0x05030000.
class SdoClient {
 public:
  SdoClient(uint8_t server_node, int64_t timeout_ns) : node_(server_node), timeout_ns_(timeout_ns) {}

  // The request frame; nullopt if a transfer is pending or size is not 0..4
  // (0: "size not indicated", 0x22, value sent as 4 bytes).
  std::optional<CanFrame> start_download(uint16_t index, uint8_t subindex, uint32_t value, uint8_t size,
                                         int64_t now_ns);
  std::optional<CanFrame> start_upload(uint16_t index, uint8_t subindex, int64_t now_ns);

  // Feeds a received frame. Frames on other COB-IDs are kIgnored; an SDO
  // response with no transfer pending, or naming another object than the
  // pending transfer's (a late answer to a request that timed out and was
  // sent again), is kMalformed (kUnexpectedSdo); one of the wrong length is
  // kMalformed (kWrongLength); the transfer stays pending after either. During a segmented upload each segment gives kPending with the
  // next segment request in to_send, until the last gives kDone.
  SdoResult on_frame(const CanFrame& frame, int64_t now_ns);
  // kAbort with 0x05040000 once the deadline has passed; else kPending.
  SdoResult poll(int64_t now_ns);
  // Gives up the pending transfer (nothing is sent).
  void cancel() { state_ = State::kIdle; }

  bool busy() const { return state_ != State::kIdle; }
  uint8_t server_node() const { return node_; }
  uint32_t response_cob_id() const;
  uint32_t request_cob_id() const;

 private:
  enum class State : uint8_t { kIdle, kDownload, kUpload, kUploadSegments };
  SdoResult finish(SdoResult::Kind kind);
  SdoResult protocol_error(const char* why, uint32_t abort_code = sdo::kAbortCommand);
  SdoResult on_download_response(uint8_t command, uint16_t index, uint8_t subindex);
  SdoResult on_upload_response(const CanFrame& frame, int64_t now_ns);
  SdoResult on_upload_segment(const CanFrame& frame, int64_t now_ns);
  SdoResult next_segment_request(int64_t now_ns);
  bool expired(int64_t now_ns) const;

  uint8_t node_;
  int64_t timeout_ns_;
  State state_ = State::kIdle;
  uint16_t index_ = 0;
  uint8_t subindex_ = 0;
  int64_t start_ns_ = 0;
  // Segmented upload in progress.
  uint8_t toggle_ = 0;
  bool size_indicated_ = false;
  uint32_t size_expected_ = 0;
  std::size_t received_ = 0;
  std::array<uint8_t, kSdoMaxUpload> bytes_{};
};

enum class Access : uint8_t { kReadOnly, kWriteOnly, kReadWrite };

// One object dictionary entry of an expedited-size object (1..4 bytes).
struct OdEntry {
  uint16_t index = 0;
  uint8_t subindex = 0;
  uint8_t size = 0;  // bytes, 1..4
  Access access = Access::kReadWrite;
  uint32_t value = 0;  // little-endian value, low `size` bytes
};

// The server side of the simulated valve node: answers expedited download
// requests and upload requests (expedited, or segmented when asked to) from
// a caller-owned table. Aborts: no such index 0x06020000, no such subindex
// 0x06090011, write to read-only 0x06010002, read of write-only 0x06010001,
// indicated size != object size 0x06070010, an entry not 1..4 bytes
// 0x06010000, a segment request out of turn or a segmented download, block
// or unknown command 0x05040001, a segment toggle bit not alternated
// 0x05030000, and whatever the write check refuses a write with.
class SdoServer {
 public:
  // The owner's rules for a write (e.g. CiA 301's for PDO mapping objects):
  // 0 accepts it, any other value is the abort code it is refused with.
  using WriteCheck = std::function<uint32_t(const OdEntry& entry, uint32_t value)>;

  SdoServer(uint8_t node, std::span<OdEntry> dictionary) : node_(node), od_(dictionary) {}

  void set_write_check(WriteCheck check) { write_check_ = std::move(check); }
  // Answer every upload with a segmented transfer (legal for any object).
  void set_segmented_uploads(bool on) { segmented_uploads_ = on; }

  // Handles a frame; returns the response to send for a request on
  // 0x600+node. Nothing is returned for frames of other COB-IDs, for an abort
  // from the client, or for a malformed request (reason in *why if given).
  std::optional<CanFrame> on_frame(const CanFrame& frame, Malformed* why = nullptr);

  OdEntry* find(uint16_t index, uint8_t subindex);
  uint8_t node() const { return node_; }
  uint32_t writes() const { return writes_; }  // successful downloads

 private:
  CanFrame abort(uint16_t index, uint8_t subindex, uint32_t code);
  CanFrame download(OdEntry& entry, uint8_t command, uint32_t data);
  CanFrame upload(const OdEntry& entry);
  CanFrame upload_segment(uint8_t command);
  uint32_t tx_cob() const;

  uint8_t node_;
  std::span<OdEntry> od_;
  uint32_t writes_ = 0;
  WriteCheck write_check_;
  bool segmented_uploads_ = false;
  // A segmented upload being served: what is left to send.
  struct Pending {
    bool active = false;
    uint16_t index = 0;
    uint8_t subindex = 0;
    uint8_t toggle = 0;
    uint8_t sent = 0;
    uint8_t size = 0;
    uint32_t value = 0;
  } pending_;
};

const char* sdo_result_kind_name(SdoResult::Kind k);

}  // namespace rigctl::canopen
