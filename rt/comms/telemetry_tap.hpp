// A second consumer of every telemetry message the publisher sends (the
// Foxglove server, foxglove/telemetry): called on the publisher thread, after
// the run log got the same bytes, never on the tick. An implementation must
// return quickly and must not wait for its own consumers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace rigctl {

class TelemetryTap {
 public:
  virtual ~TelemetryTap() = default;
  // channel: the LCM channel name; utime: the message's time stamp [us since
  // the epoch]; data/size: the LCM-encoded message.
  virtual void on_message(const std::string& channel, int64_t utime, const uint8_t* data, std::size_t size) noexcept = 0;
};

}  // namespace rigctl
