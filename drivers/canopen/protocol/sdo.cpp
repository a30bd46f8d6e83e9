#include "drivers/canopen/protocol/sdo.hpp"

#include "drivers/canopen/protocol/cob_id.hpp"

namespace rigctl::canopen {

namespace {

constexpr uint32_t size_mask(uint8_t size) {
  return size == 0 || size >= 4 ? 0xFFFFFFFFU : (1U << (8U * size)) - 1U;
}

CanFrame sdo_frame(uint32_t cob, uint8_t command, uint16_t index, uint8_t subindex, uint32_t data) {
  CanFrame f;
  f.can_id = cob & kCanSffMask;
  f.len = 8;
  f.data[0] = command;
  put_u16le(&f.data[1], index);
  f.data[3] = subindex;
  put_u32le(&f.data[4], data);
  return f;
}

}  // namespace

const char* abort_code_text(uint32_t code) {
  using namespace sdo;
  switch (code) {
    case kAbortToggleBit: return "toggle bit not alternated";
    case kAbortTimeout: return "SDO protocol timed out";
    case kAbortCommand: return "client/server command specifier not valid or unknown";
    case kAbortBlockSize: return "invalid block size";
    case kAbortSequence: return "invalid sequence number";
    case kAbortCrc: return "CRC error";
    case kAbortOutOfMemory: return "out of memory";
    case kAbortUnsupportedAccess: return "unsupported access to an object";
    case kAbortWriteOnly: return "attempt to read a write-only object";
    case kAbortReadOnly: return "attempt to write a read-only object";
    case kAbortNoObject: return "object does not exist in the object dictionary";
    case kAbortNotMappable: return "object cannot be mapped to the PDO";
    case kAbortPdoLength: return "number and length of objects to be mapped would exceed the PDO length";
    case kAbortParameterIncompatible: return "general parameter incompatibility";
    case kAbortInternalIncompatible: return "general internal incompatibility in the device";
    case kAbortHardware: return "access failed due to a hardware error";
    case kAbortLengthMismatch: return "data type does not match, length of service parameter does not match";
    case kAbortLengthTooHigh: return "data type does not match, length of service parameter too high";
    case kAbortLengthTooLow: return "data type does not match, length of service parameter too low";
    case kAbortNoSubindex: return "sub-index does not exist";
    case kAbortInvalidValue: return "invalid value for parameter";
    case kAbortValueTooHigh: return "value of parameter written too high";
    case kAbortValueTooLow: return "value of parameter written too low";
    case kAbortMaxLessThanMin: return "maximum value is less than minimum value";
    case kAbortResourceNotAvailable: return "resource not available: SDO connection";
    case kAbortGeneral: return "general error";
    case kAbortCannotStore: return "data cannot be transferred or stored to the application";
    case kAbortLocalControl: return "data cannot be transferred or stored to the application because of local control";
    case kAbortDeviceState: return "data cannot be transferred or stored to the application because of the present device state";
    case kAbortNoDictionary: return "object dictionary dynamic generation failed or no object dictionary is present";
    case kAbortNoData: return "no data available";
    default: return "unknown abort code";
  }
}

CanFrame sdo_download_request(uint8_t node, uint16_t index, uint8_t subindex, uint32_t value, uint8_t size) {
  uint8_t command = sdo::kDownloadNoSize;
  switch (size) {
    case 1: command = sdo::kDownload1; break;
    case 2: command = sdo::kDownload2; break;
    case 3: command = sdo::kDownload3; break;
    case 4: command = sdo::kDownload4; break;
    default: break;
  }
  return sdo_frame(kCobSdoRxBase + (node & 0x7F), command, index, subindex, value & size_mask(size));
}

CanFrame sdo_upload_request(uint8_t node, uint16_t index, uint8_t subindex) {
  return sdo_frame(kCobSdoRxBase + (node & 0x7F), sdo::kUploadRequest, index, subindex, 0);
}

CanFrame sdo_abort(uint32_t cob, uint16_t index, uint8_t subindex, uint32_t code) {
  return sdo_frame(cob, sdo::kAbort, index, subindex, code);
}

// ---------------------------------------------------------------- client

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

SdoResult SdoClient::protocol_error(const char* why) {
  SdoResult r = finish(SdoResult::Kind::kProtocolError);
  r.abort_code = sdo::kAbortCommand;
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
  if (!busy()) {
    r.kind = SdoResult::Kind::kMalformed;
    r.malformed = Malformed::kUnexpectedSdo;
    r.text = "SDO response with no transfer pending";
    return r;
  }
  if (expired(now_ns)) return poll(now_ns);
  if (frame.len != 8) {
    r.kind = SdoResult::Kind::kMalformed;
    r.malformed = Malformed::kWrongLength;
    r.index = index_;
    r.subindex = subindex_;
    r.text = "SDO frame not 8 bytes";
    return r;
  }

  const uint8_t command = frame.data[0];
  const uint16_t index = get_u16le(&frame.data[1]);
  const uint8_t subindex = frame.data[3];
  const uint32_t data = get_u32le(&frame.data[4]);

  if (command == sdo::kAbort) {
    // Accepted whatever multiplexer it echoes: one transfer at a time on this
    // channel, and some servers abort an unintelligible request with 0/0.
    r = finish(SdoResult::Kind::kAbort);
    r.abort_code = data;
    r.text = abort_code_text(data);
    return r;
  }

  uint8_t size = 0;
  if (state_ == State::kDownload) {
    if (command != sdo::kDownloadResponse) return protocol_error("unexpected command byte in download response");
  } else {
    switch (command) {
      case sdo::kUpload1: size = 1; break;
      case sdo::kUpload2: size = 2; break;
      case sdo::kUpload3: size = 3; break;
      case sdo::kUpload4: size = 4; break;
      case sdo::kUploadNoSize: size = 0; break;
      case 0x40:
      case 0x41: return protocol_error("segmented upload not supported");
      default: return protocol_error("unexpected command byte in upload response");
    }
  }
  if (index != index_ || subindex != subindex_) {
    SdoResult e = protocol_error("response for another index/subindex");
    e.abort_code = sdo::kAbortGeneral;
    e.to_send = sdo_abort(request_cob_id(), index_, subindex_, e.abort_code);
    return e;
  }
  const bool upload = state_ == State::kUpload;
  r = finish(SdoResult::Kind::kDone);
  if (upload) {
    r.size = size;
    r.value = data & size_mask(size);
  }
  return r;
}

// ---------------------------------------------------------------- server

OdEntry* SdoServer::find(uint16_t index, uint8_t subindex) {
  for (auto& e : od_) {
    if (e.index == index && e.subindex == subindex) return &e;
  }
  return nullptr;
}

CanFrame SdoServer::abort(uint16_t index, uint8_t subindex, uint32_t code) const {
  return sdo_abort(kCobSdoTxBase + (node_ & 0x7F), index, subindex, code);
}

std::optional<CanFrame> SdoServer::on_frame(const CanFrame& frame, Malformed* why) {
  if (why) *why = Malformed::kNone;
  if (!frame.is_standard_data() || frame.id() != kCobSdoRxBase + (node_ & 0x7F)) return std::nullopt;
  if (frame.len != 8) {
    if (why) *why = Malformed::kWrongLength;
    return std::nullopt;
  }
  const uint8_t command = frame.data[0];
  const uint8_t ccs = command >> 5;
  const uint16_t index = get_u16le(&frame.data[1]);
  const uint8_t subindex = frame.data[3];

  if (ccs == 4) return std::nullopt;  // abort from the client: nothing pending here, nothing to answer
  if (ccs != 1 && ccs != 2) return abort(index, subindex, sdo::kAbortCommand);
  if (ccs == 1 && (command & 0x02) == 0) return abort(index, subindex, sdo::kAbortCommand);  // segmented

  OdEntry* entry = find(index, subindex);
  if (entry == nullptr) {
    bool index_exists = false;
    for (const auto& e : od_) index_exists = index_exists || e.index == index;
    return abort(index, subindex, index_exists ? sdo::kAbortNoSubindex : sdo::kAbortNoObject);
  }
  if (entry->size < 1 || entry->size > 4) return abort(index, subindex, sdo::kAbortUnsupportedAccess);

  if (ccs == 1) {  // expedited download
    if (entry->access == Access::kReadOnly) return abort(index, subindex, sdo::kAbortReadOnly);
    if (command & 0x01) {
      const uint8_t size = static_cast<uint8_t>(4 - ((command >> 2) & 0x03));
      if (size != entry->size) return abort(index, subindex, sdo::kAbortLengthMismatch);
    }
    entry->value = get_u32le(&frame.data[4]) & size_mask(entry->size);
    ++writes_;
    return sdo_frame(kCobSdoTxBase + (node_ & 0x7F), sdo::kDownloadResponse, index, subindex, 0);
  }
  // expedited upload
  if (entry->access == Access::kWriteOnly) return abort(index, subindex, sdo::kAbortWriteOnly);
  const auto response = static_cast<uint8_t>(0x43 | ((4 - entry->size) << 2));
  return sdo_frame(kCobSdoTxBase + (node_ & 0x7F), response, index, subindex, entry->value & size_mask(entry->size));
}

const char* sdo_result_kind_name(SdoResult::Kind k) {
  switch (k) {
    case SdoResult::Kind::kPending: return "pending";
    case SdoResult::Kind::kDone: return "done";
    case SdoResult::Kind::kAbort: return "abort";
    case SdoResult::Kind::kProtocolError: return "protocol error";
    case SdoResult::Kind::kIgnored: return "ignored";
    case SdoResult::Kind::kMalformed: return "malformed";
  }
  return "?";
}

}  // namespace rigctl::canopen
