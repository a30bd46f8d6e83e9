// CRC-32 (ISO-HDLC, the zlib/PNG one: reflected polynomial 0xEDB88320), as
// the MCAP specification uses for chunks, the data section and the summary.
#pragma once

#include <cstddef>
#include <cstdint>

namespace rigctl::mcap {

class Crc32 {
 public:
  void update(const void* data, std::size_t size);
  uint32_t value() const { return ~state_; }

 private:
  uint32_t state_ = 0xFFFFFFFFu;
};

uint32_t crc32(const void* data, std::size_t size);

}  // namespace rigctl::mcap
