// The SDO server of the simulated valve node (CiA 301): expedited downloads,
// expedited or segmented uploads, from a caller-owned object dictionary.
#include <algorithm>

#include "drivers/canopen/protocol/cob_id.hpp"
#include "drivers/canopen/protocol/sdo.hpp"

namespace rigctl::canopen {

OdEntry* SdoServer::find(uint16_t index, uint8_t subindex) {
  for (auto& e : od_) {
    if (e.index == index && e.subindex == subindex) return &e;
  }
  return nullptr;
}

uint32_t SdoServer::tx_cob() const { return kCobSdoTxBase + (node_ & 0x7F); }

CanFrame SdoServer::abort(uint16_t index, uint8_t subindex, uint32_t code) {
  pending_.active = false;
  return sdo_abort(tx_cob(), index, subindex, code);
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

  if (ccs == 4) {  // abort from the client: nothing to answer
    pending_.active = false;
    return std::nullopt;
  }
  if (ccs == 3 && pending_.active) return upload_segment(command);
  if (ccs != 1 && ccs != 2) return abort(index, subindex, sdo::kAbortCommand);
  if (ccs == 1 && (command & 0x02) == 0) return abort(index, subindex, sdo::kAbortCommand);  // segmented download
  pending_.active = false;  // a new request ends a segmented upload left unfinished

  OdEntry* entry = find(index, subindex);
  if (entry == nullptr) {
    bool index_exists = false;
    for (const auto& e : od_) index_exists = index_exists || e.index == index;
    return abort(index, subindex, index_exists ? sdo::kAbortNoSubindex : sdo::kAbortNoObject);
  }
  if (entry->size < 1 || entry->size > 4) return abort(index, subindex, sdo::kAbortUnsupportedAccess);
  if (ccs == 1) return download(*entry, command, get_u32le(&frame.data[4]));
  if (entry->access == Access::kWriteOnly) return abort(index, subindex, sdo::kAbortWriteOnly);
  return upload(*entry);
}

CanFrame SdoServer::download(OdEntry& entry, uint8_t command, uint32_t data) {
  if (entry.access == Access::kReadOnly) return abort(entry.index, entry.subindex, sdo::kAbortReadOnly);
  if (command & 0x01) {
    const uint8_t size = static_cast<uint8_t>(4 - ((command >> 2) & 0x03));
    if (size != entry.size) return abort(entry.index, entry.subindex, sdo::kAbortLengthMismatch);
  }
  const uint32_t value = data & sdo_size_mask(entry.size);
  if (write_check_) {
    if (const uint32_t refused = write_check_(entry, value); refused != 0) {
      return abort(entry.index, entry.subindex, refused);
    }
  }
  entry.value = value;
  ++writes_;
  return sdo_frame(tx_cob(), sdo::kDownloadResponse, entry.index, entry.subindex, 0);
}

CanFrame SdoServer::upload(const OdEntry& entry) {
  const uint32_t value = entry.value & sdo_size_mask(entry.size);
  if (!segmented_uploads_) {
    const auto response = static_cast<uint8_t>(0x43 | ((4 - entry.size) << 2));
    return sdo_frame(tx_cob(), response, entry.index, entry.subindex, value);
  }
  pending_ = {true, entry.index, entry.subindex, 0, 0, entry.size, value};
  return sdo_frame(tx_cob(), sdo::kUploadSegmentedSize, entry.index, entry.subindex, entry.size);
}

CanFrame SdoServer::upload_segment(uint8_t command) {
  Pending& p = pending_;
  const uint8_t toggle = (command & sdo::kToggleBit) ? 1 : 0;
  if ((command & 0x0F) != 0 || (command & 0xE0) != 0x60) return abort(p.index, p.subindex, sdo::kAbortCommand);
  if (toggle != p.toggle) return abort(p.index, p.subindex, sdo::kAbortToggleBit);
  const uint8_t count = static_cast<uint8_t>(std::min<int>(7, p.size - p.sent));
  const bool last = p.sent + count >= p.size;
  CanFrame f;
  f.can_id = tx_cob();
  f.len = 8;
  f.data[0] = static_cast<uint8_t>((toggle ? sdo::kToggleBit : 0) | ((7 - count) << 1) | (last ? 1 : 0));
  for (uint8_t i = 0; i < count; ++i) f.data[1 + i] = static_cast<uint8_t>(p.value >> (8 * (p.sent + i)));
  p.sent = static_cast<uint8_t>(p.sent + count);
  p.toggle ^= 1U;
  if (last) p.active = false;
  return f;
}

}  // namespace rigctl::canopen
