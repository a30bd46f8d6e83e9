// How the analogue outputs are written: contiguous holding registers of one
// unit go out in one request, so the outputs of one cycle change together.
// Start-up code; throws std::invalid_argument.
#pragma once

#include <span>
#include <vector>

#include "drivers/modbus/modbus_codec.hpp"

namespace rigctl {

// The most registers one FC 16 request may write (Modbus spec 6.12).
inline constexpr int kMaxWriteRegisters = 123;

struct WriteBlock {
  int unit_id = 0;
  int address = 0;
  int count = 0;
};

struct WritePlan {
  std::vector<WriteBlock> blocks;    // sorted by unit id, then address
  std::vector<PointLocation> where;  // one per output point, in the output order
};

// Groups the points into runs of adjacent registers (no gaps: a gap would
// overwrite a register nobody configured). Every point must be a holding
// register, and no two points may share a register: two outputs driving one
// register would fight. Errors name the point's index.
WritePlan plan_writes(std::span<const ModbusPoint> points);

}  // namespace rigctl
