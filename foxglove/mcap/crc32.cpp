#include "foxglove/mcap/crc32.hpp"

#include <array>

namespace rigctl::mcap {

namespace {

constexpr std::array<uint32_t, 256> make_table() {
  std::array<uint32_t, 256> table{};
  for (uint32_t i = 0; i < 256; ++i) {
    uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) != 0 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    table[i] = c;
  }
  return table;
}

constexpr std::array<uint32_t, 256> kTable = make_table();

}  // namespace

void Crc32::update(const void* data, std::size_t size) {
  const auto* p = static_cast<const uint8_t*>(data);
  for (std::size_t i = 0; i < size; ++i) state_ = kTable[(state_ ^ p[i]) & 0xFFu] ^ (state_ >> 8);
}

uint32_t crc32(const void* data, std::size_t size) {
  Crc32 c;
  c.update(data, size);
  return c.value();
}

}  // namespace rigctl::mcap
