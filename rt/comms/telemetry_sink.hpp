// Where the loop hands its per-tick record. Implementations must never block.
#pragma once

#include "rt/telemetry_record.hpp"

namespace rigctl {

class TelemetrySink {
 public:
  virtual ~TelemetrySink() = default;
  // Returns false when the record had to be dropped.
  virtual bool push(const TelemetryRecord& record) noexcept = 0;
};

}  // namespace rigctl
