// The only SocketCAN-specific code: open a CAN_RAW socket on a named
// interface with kernel receive filters. Everything above it works on the
// CanTransport fd and is tested over SOCK_SEQPACKET sockets instead, because
// the development and CI kernel has no CAN (socket(PF_CAN) fails with
// EAFNOSUPPORT); here only the failure path can be exercised.
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "drivers/canopen/can_transport.hpp"

namespace rigctl {

// A CAN_RAW socket bound to `interface` (e.g. "can0") that receives only
// standard data frames with the given 11-bit COB-IDs (CAN_RAW_FILTER; an
// empty list receives nothing). Throws std::runtime_error naming the
// interface and the reason; when the kernel lacks AF_CAN the message says so.
CanTransport open_socketcan(const std::string& interface, std::span<const uint32_t> cob_ids);

}  // namespace rigctl
