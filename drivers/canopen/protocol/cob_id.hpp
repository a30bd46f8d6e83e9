// CiA 301 pre-defined connection set: which service a COB-ID belongs to and
// which node sent it, and the COB-IDs to send on.
//
//   NMT 0x000, SYNC 0x080, EMCY 0x080+node, TIME 0x100,
//   TPDO1..4 0x180/0x280/0x380/0x480+node, RPDO1..4 0x200/0x300/0x400/0x500+node,
//   SDO server->client (tx) 0x580+node, client->server (rx) 0x600+node,
//   NMT error control (heartbeat, boot-up) 0x700+node; node ids 1..127.
//
// "tx"/"rx" are as seen from the device (the valve): the valve transmits TPDOs
// and SDO responses, receives RPDOs and SDO requests.
#pragma once

#include <cstdint>

#include "drivers/canopen/protocol/can_frame.hpp"
#include "drivers/canopen/protocol/frame_stats.hpp"

namespace rigctl::canopen {

enum class Function : uint8_t {
  kUnknown = 0,
  kNmt,
  kSync,
  kEmcy,
  kTime,
  kTpdo1,
  kTpdo2,
  kTpdo3,
  kTpdo4,
  kRpdo1,
  kRpdo2,
  kRpdo3,
  kRpdo4,
  kSdoTx,      // SDO response (server -> client), 0x580+node
  kSdoRx,      // SDO request (client -> server), 0x600+node
  kHeartbeat,  // NMT error control, 0x700+node
};

inline constexpr uint8_t kMinNodeId = 1;
inline constexpr uint8_t kMaxNodeId = 127;
constexpr bool valid_node_id(unsigned node) { return node >= kMinNodeId && node <= kMaxNodeId; }

inline constexpr uint32_t kCobNmt = 0x000;
inline constexpr uint32_t kCobSync = 0x080;
inline constexpr uint32_t kCobEmcyBase = 0x080;
inline constexpr uint32_t kCobTime = 0x100;
inline constexpr uint32_t kCobTpdoBase[4] = {0x180, 0x280, 0x380, 0x480};
inline constexpr uint32_t kCobRpdoBase[4] = {0x200, 0x300, 0x400, 0x500};
inline constexpr uint32_t kCobSdoTxBase = 0x580;
inline constexpr uint32_t kCobSdoRxBase = 0x600;
inline constexpr uint32_t kCobHeartbeatBase = 0x700;

struct CobInfo {
  Function function = Function::kUnknown;
  uint8_t node = 0;  // 1..127; 0 for the broadcast services NMT, SYNC, TIME
  bool operator==(const CobInfo&) const = default;
};

// Service and node of an 11-bit COB-ID; kUnknown for anything outside the set
// above (node 0 of a per-node service, 0x680..0x6FF, 0x780..0x7FF, ids > 0x7FF).
CobInfo classify_cob_id(uint32_t cob_id);

// As classify_cob_id, and kUnknown for a frame that is not a standard data frame.
CobInfo classify(const CanFrame& frame);

// Classifies the frame and checks what can be checked without knowing the
// node's configuration: a standard data frame, a known COB-ID, len <= 8 and
// the fixed length of the service (NMT 2, SYNC 0 or 1, TIME 6, EMCY 8, SDO 8,
// heartbeat 1; PDOs 0..8, their exact length depends on the mapping).
Malformed check_frame(const CanFrame& frame, CobInfo& info);
// As check_frame, for a decoder of one service: kUnknownCobId when the frame
// belongs to another service (checked before the length).
Malformed check_frame_for(const CanFrame& frame, Function expected, CobInfo& info);

// COB-ID of a per-node service for `node` (1..127), of NMT/SYNC/TIME (node
// ignored); 0xFFFFFFFF for kUnknown or an invalid node id.
uint32_t cob_id(Function function, uint8_t node);

// TPDO/RPDO n (1..4) as a Function; kUnknown for other n.
Function tpdo(int n);
Function rpdo(int n);
// 1..4 for a PDO function, 0 otherwise.
int pdo_number(Function f);
bool is_tpdo(Function f);
bool is_rpdo(Function f);

const char* function_name(Function f);

}  // namespace rigctl::canopen
