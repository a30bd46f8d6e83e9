// SDO frames and abort codes, shared by the client (sdo_client.cpp) and the
// server (sdo_server.cpp).
#include "drivers/canopen/protocol/sdo.hpp"

#include "drivers/canopen/protocol/cob_id.hpp"

namespace rigctl::canopen {

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
  return sdo_frame(kCobSdoRxBase + (node & 0x7F), command, index, subindex, value & sdo_size_mask(size));
}

CanFrame sdo_upload_request(uint8_t node, uint16_t index, uint8_t subindex) {
  return sdo_frame(kCobSdoRxBase + (node & 0x7F), sdo::kUploadRequest, index, subindex, 0);
}

CanFrame sdo_abort(uint32_t cob, uint16_t index, uint8_t subindex, uint32_t code) {
  return sdo_frame(cob, sdo::kAbort, index, subindex, code);
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
