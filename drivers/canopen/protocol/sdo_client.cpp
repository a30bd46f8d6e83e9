// The SDO client (CiA 301): one transfer at a time, expedited downloads,
// expedited and segmented uploads.
#include <algorithm>

#include "drivers/canopen/protocol/cob_id.hpp"
#include "drivers/canopen/protocol/sdo.hpp"

namespace rigctl::canopen {

namespace {
// A frame of this client's channel that is not used (counted by the caller).
SdoResult dropped(Malformed why, uint16_t index, uint8_t subindex, const char* text) {
  SdoResult r;
  r.kind = SdoResult::Kind::kMalformed;
  r.malformed = why;
  r.index = index;
  r.subindex = subindex;
  r.text = text;
  return r;
}
}  // namespace

uint32_t SdoClient::response_cob_id() const { return kCobSdoTxBase + (node_ & 0x7F); }
uint32_t SdoClient::request_cob_id() const { return kCobSdoRxBase + (node_ & 0x7F); }

std::optional<CanFrame> SdoClient::start_download(uint16_t index, uint8_t subindex, uint32_t value, uint8_t size,
                                                  int64_t now_ns) {
  if (busy() || size > 4) return std::nullopt;
  state_ = State::kDownload;
  index_ = index;
  subindex_ = subindex;
  start_ns_ = now_ns;
  return sdo_download_request(node_, index, subindex, value, size);
}

std::optional<CanFrame> SdoClient::start_upload(uint16_t index, uint8_t subindex, int64_t now_ns) {
  if (busy()) return std::nullopt;
  state_ = State::kUpload;
  index_ = index;
  subindex_ = subindex;
  start_ns_ = now_ns;
  return sdo_upload_request(node_, index, subindex);
}

bool SdoClient::expired(int64_t now_ns) const {
  if (now_ns <= start_ns_) return false;
  const uint64_t waited = static_cast<uint64_t>(now_ns) - static_cast<uint64_t>(start_ns_);
  return timeout_ns_ >= 0 && waited > static_cast<uint64_t>(timeout_ns_);
}

SdoResult SdoClient::finish(SdoResult::Kind kind) {
  SdoResult r;
  r.kind = kind;
  r.index = index_;
  r.subindex = subindex_;
  state_ = State::kIdle;
  return r;
}

SdoResult SdoClient::protocol_error(const char* why, uint32_t abort_code) {
  SdoResult r = finish(SdoResult::Kind::kProtocolError);
  r.abort_code = abort_code;
  r.text = why;
  r.to_send = sdo_abort(request_cob_id(), index_, subindex_, r.abort_code);
  return r;
}

SdoResult SdoClient::poll(int64_t now_ns) {
  if (!busy() || !expired(now_ns)) {
    SdoResult r;
    r.index = index_;
    r.subindex = subindex_;
    return r;
  }
  SdoResult r = finish(SdoResult::Kind::kAbort);
  r.abort_code = sdo::kAbortTimeout;
  r.text = abort_code_text(r.abort_code);
  r.to_send = sdo_abort(request_cob_id(), index_, subindex_, r.abort_code);
  return r;
}

SdoResult SdoClient::on_frame(const CanFrame& frame, int64_t now_ns) {
  SdoResult r;
  if (!frame.is_standard_data() || frame.id() != response_cob_id()) {
    r.kind = SdoResult::Kind::kIgnored;
    return r;
  }
  if (!busy()) return dropped(Malformed::kUnexpectedSdo, 0, 0, "SDO response with no transfer pending");
  if (expired(now_ns)) return poll(now_ns);
  if (frame.len != 8) return dropped(Malformed::kWrongLength, index_, subindex_, "SDO frame not 8 bytes");

  const uint8_t command = frame.data[0];
  if (command == sdo::kAbort) {
    // Accepted whatever multiplexer it echoes: one transfer at a time on this
    // channel, and some servers abort an unintelligible request with 0/0.
    r = finish(SdoResult::Kind::kAbort);
    r.abort_code = get_u32le(&frame.data[4]);
    r.text = abort_code_text(r.abort_code);
    return r;
  }
  switch (state_) {
    case State::kDownload: return on_download_response(command, get_u16le(&frame.data[1]), frame.data[3]);
    case State::kUpload: return on_upload_response(frame, now_ns);
    case State::kUploadSegments: return on_upload_segment(frame, now_ns);
    case State::kIdle: break;
  }
  return protocol_error("response with no transfer pending");
}

namespace {
// An answer naming another object than the pending transfer's: a late
// answer to an earlier request (one that timed out and was sent again) is
// the usual one. Dropped, the transfer goes on waiting for its own.
SdoResult stale_answer(uint16_t index, uint8_t subindex) {
  return dropped(Malformed::kUnexpectedSdo, index, subindex,
                 "SDO response for another index/subindex (a late answer to an earlier request?)");
}
}  // namespace

SdoResult SdoClient::on_download_response(uint8_t command, uint16_t index, uint8_t subindex) {
  // The multiplexer is only one in a response of the right kind (scs 3).
  if ((command & 0xE0) != sdo::kDownloadResponse) return protocol_error("unexpected command byte in download response");
  if (index != index_ || subindex != subindex_) return stale_answer(index_, subindex_);
  if (command != sdo::kDownloadResponse) return protocol_error("unexpected command byte in download response");
  return finish(SdoResult::Kind::kDone);
}

SdoResult SdoClient::on_upload_response(const CanFrame& frame, int64_t now_ns) {
  const uint8_t command = frame.data[0];
  // The multiplexer is only one in a response of the right kind (scs 2).
  if ((command & 0xE0) != sdo::kUploadSegmented) return protocol_error("unexpected command byte in upload response");
  if (get_u16le(&frame.data[1]) != index_ || frame.data[3] != subindex_) return stale_answer(index_, subindex_);
  uint8_t size = 0;
  bool segmented = false;
  switch (command) {
    case sdo::kUpload1: size = 1; break;
    case sdo::kUpload2: size = 2; break;
    case sdo::kUpload3: size = 3; break;
    case sdo::kUpload4: size = 4; break;
    case sdo::kUploadNoSize: size = 0; break;
    case sdo::kUploadSegmented:
    case sdo::kUploadSegmentedSize: segmented = true; break;
    default: return protocol_error("unexpected command byte in upload response");
  }
  const uint32_t data = get_u32le(&frame.data[4]);
  if (segmented) {
    size_indicated_ = command == sdo::kUploadSegmentedSize;
    size_expected_ = data;
    if (size_indicated_ && size_expected_ > kSdoMaxUpload) {
      return protocol_error("segmented upload longer than the client takes (64 bytes)", sdo::kAbortOutOfMemory);
    }
    state_ = State::kUploadSegments;
    toggle_ = 0;
    received_ = 0;
    return next_segment_request(now_ns);
  }
  SdoResult r = finish(SdoResult::Kind::kDone);
  r.size = size;
  r.value = data & sdo_size_mask(size);
  std::copy(&frame.data[4], &frame.data[8], r.bytes.begin());
  return r;
}

SdoResult SdoClient::next_segment_request(int64_t now_ns) {
  start_ns_ = now_ns;  // each segment has its own timeout
  SdoResult r;
  r.index = index_;
  r.subindex = subindex_;
  r.to_send = sdo_frame(request_cob_id(), static_cast<uint8_t>(sdo::kUploadSegmentRequest | (toggle_ ? sdo::kToggleBit : 0)),
                        0, 0, 0);
  return r;
}

SdoResult SdoClient::on_upload_segment(const CanFrame& frame, int64_t now_ns) {
  const uint8_t command = frame.data[0];
  if ((command & 0xE0) != 0) return protocol_error("unexpected command byte in upload segment");
  if (((command & sdo::kToggleBit) != 0) != (toggle_ != 0)) {
    return protocol_error("upload segment with the toggle bit not alternated", sdo::kAbortToggleBit);
  }
  const std::size_t count = 7U - ((command >> 1) & 0x07U);
  if (received_ + count > kSdoMaxUpload) {
    return protocol_error("segmented upload longer than the client takes (64 bytes)", sdo::kAbortOutOfMemory);
  }
  std::copy(&frame.data[1], &frame.data[1 + count], bytes_.begin() + static_cast<std::ptrdiff_t>(received_));
  received_ += count;
  if ((command & 0x01) == 0) {
    toggle_ ^= 1U;
    return next_segment_request(now_ns);
  }
  if (size_indicated_ && received_ != size_expected_) {
    return protocol_error("segmented upload ended with another size than it announced", sdo::kAbortLengthMismatch);
  }
  SdoResult r = finish(SdoResult::Kind::kDone);
  r.segmented = true;
  r.size = static_cast<uint8_t>(received_);
  r.bytes = bytes_;
  for (std::size_t i = 0; i < std::min<std::size_t>(received_, 4); ++i) r.value |= static_cast<uint32_t>(bytes_[i]) << (8 * i);
  return r;
}

}  // namespace rigctl::canopen
