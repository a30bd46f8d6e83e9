#include "drivers/canopen/protocol/cob_id.hpp"

namespace rigctl::canopen {

CobInfo classify_cob_id(uint32_t id) {
  if (id > kCanSffMask) return {};
  const auto code = id >> 7;                       // function code, 4 bits
  const auto node = static_cast<uint8_t>(id & 0x7F);  // node id, 7 bits
  auto per_node = [node](Function f) { return node == 0 ? CobInfo{} : CobInfo{f, node}; };
  switch (code) {
    case 0x0: return node == 0 ? CobInfo{Function::kNmt, 0} : CobInfo{};
    case 0x1: return node == 0 ? CobInfo{Function::kSync, 0} : CobInfo{Function::kEmcy, node};
    case 0x2: return node == 0 ? CobInfo{Function::kTime, 0} : CobInfo{};
    case 0x3: return per_node(Function::kTpdo1);
    case 0x4: return per_node(Function::kRpdo1);
    case 0x5: return per_node(Function::kTpdo2);
    case 0x6: return per_node(Function::kRpdo2);
    case 0x7: return per_node(Function::kTpdo3);
    case 0x8: return per_node(Function::kRpdo3);
    case 0x9: return per_node(Function::kTpdo4);
    case 0xA: return per_node(Function::kRpdo4);
    case 0xB: return per_node(Function::kSdoTx);
    case 0xC: return per_node(Function::kSdoRx);
    case 0xE: return per_node(Function::kHeartbeat);
    default: return {};  // 0xD (0x680..0x6FF) and 0xF (0x780..0x7FF, LSS etc.) are not used here
  }
}

CobInfo classify(const CanFrame& frame) {
  if (!frame.is_standard_data()) return {};
  return classify_cob_id(frame.can_id);
}

namespace {

bool length_ok(Function f, uint8_t len) {
  if (len > kCanMaxDataLen) return false;
  switch (f) {
    case Function::kNmt: return len == 2;
    case Function::kSync: return len <= 1;  // 1 with the optional SYNC counter
    case Function::kTime: return len == 6;
    case Function::kEmcy: return len == 8;
    case Function::kSdoTx:
    case Function::kSdoRx: return len == 8;
    case Function::kHeartbeat: return len == 1;
    default: return true;  // PDOs: checked against the mapping
  }
}

}  // namespace

Malformed check_frame(const CanFrame& frame, CobInfo& info) {
  info = {};
  if (!frame.is_standard_data()) return Malformed::kNotDataFrame;
  info = classify_cob_id(frame.can_id);
  if (info.function == Function::kUnknown) return Malformed::kUnknownCobId;
  return length_ok(info.function, frame.len) ? Malformed::kNone : Malformed::kWrongLength;
}

Malformed check_frame_for(const CanFrame& frame, Function expected, CobInfo& info) {
  info = {};
  if (!frame.is_standard_data()) return Malformed::kNotDataFrame;
  info = classify_cob_id(frame.can_id);
  if (info.function != expected || expected == Function::kUnknown) return Malformed::kUnknownCobId;
  return length_ok(info.function, frame.len) ? Malformed::kNone : Malformed::kWrongLength;
}

uint32_t cob_id(Function f, uint8_t node) {
  constexpr uint32_t kInvalid = 0xFFFFFFFFU;
  switch (f) {
    case Function::kNmt: return kCobNmt;
    case Function::kSync: return kCobSync;
    case Function::kTime: return kCobTime;
    case Function::kUnknown: return kInvalid;
    default: break;
  }
  if (!valid_node_id(node)) return kInvalid;
  switch (f) {
    case Function::kEmcy: return kCobEmcyBase + node;
    case Function::kTpdo1: return kCobTpdoBase[0] + node;
    case Function::kTpdo2: return kCobTpdoBase[1] + node;
    case Function::kTpdo3: return kCobTpdoBase[2] + node;
    case Function::kTpdo4: return kCobTpdoBase[3] + node;
    case Function::kRpdo1: return kCobRpdoBase[0] + node;
    case Function::kRpdo2: return kCobRpdoBase[1] + node;
    case Function::kRpdo3: return kCobRpdoBase[2] + node;
    case Function::kRpdo4: return kCobRpdoBase[3] + node;
    case Function::kSdoTx: return kCobSdoTxBase + node;
    case Function::kSdoRx: return kCobSdoRxBase + node;
    case Function::kHeartbeat: return kCobHeartbeatBase + node;
    default: return kInvalid;
  }
}

Function tpdo(int n) {
  switch (n) {
    case 1: return Function::kTpdo1;
    case 2: return Function::kTpdo2;
    case 3: return Function::kTpdo3;
    case 4: return Function::kTpdo4;
    default: return Function::kUnknown;
  }
}

Function rpdo(int n) {
  switch (n) {
    case 1: return Function::kRpdo1;
    case 2: return Function::kRpdo2;
    case 3: return Function::kRpdo3;
    case 4: return Function::kRpdo4;
    default: return Function::kUnknown;
  }
}

int pdo_number(Function f) {
  switch (f) {
    case Function::kTpdo1:
    case Function::kRpdo1: return 1;
    case Function::kTpdo2:
    case Function::kRpdo2: return 2;
    case Function::kTpdo3:
    case Function::kRpdo3: return 3;
    case Function::kTpdo4:
    case Function::kRpdo4: return 4;
    default: return 0;
  }
}

bool is_tpdo(Function f) {
  return f == Function::kTpdo1 || f == Function::kTpdo2 || f == Function::kTpdo3 || f == Function::kTpdo4;
}
bool is_rpdo(Function f) {
  return f == Function::kRpdo1 || f == Function::kRpdo2 || f == Function::kRpdo3 || f == Function::kRpdo4;
}

const char* function_name(Function f) {
  switch (f) {
    case Function::kUnknown: return "unknown";
    case Function::kNmt: return "NMT";
    case Function::kSync: return "SYNC";
    case Function::kEmcy: return "EMCY";
    case Function::kTime: return "TIME";
    case Function::kTpdo1: return "TPDO1";
    case Function::kTpdo2: return "TPDO2";
    case Function::kTpdo3: return "TPDO3";
    case Function::kTpdo4: return "TPDO4";
    case Function::kRpdo1: return "RPDO1";
    case Function::kRpdo2: return "RPDO2";
    case Function::kRpdo3: return "RPDO3";
    case Function::kRpdo4: return "RPDO4";
    case Function::kSdoTx: return "SDO tx";
    case Function::kSdoRx: return "SDO rx";
    case Function::kHeartbeat: return "heartbeat";
  }
  return "?";
}

}  // namespace rigctl::canopen
