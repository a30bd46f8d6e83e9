// MCAP's primitive encodings (little endian): integers, strings and byte
// arrays with a uint32 length, maps and arrays with a uint32 byte length, and
// a record: opcode, uint64 content length, content.
#pragma once

#include <cstdint>
#include <string>

namespace rigctl::mcap {

enum class Opcode : uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

inline constexpr char kMagic[] = {'\x89', 'M', 'C', 'A', 'P', '0', '\r', '\n'};

class Bytes {
 public:
  Bytes& u8(uint8_t v) { return put(v, 1); }
  Bytes& u16(uint16_t v) { return put(v, 2); }
  Bytes& u32(uint32_t v) { return put(v, 4); }
  Bytes& u64(uint64_t v) { return put(v, 8); }
  Bytes& str(const std::string& s) {  // string, and byte array with a uint32 length
    u32(static_cast<uint32_t>(s.size()));
    out_ += s;
    return *this;
  }
  Bytes& raw(const std::string& s) {
    out_ += s;
    return *this;
  }
  // A map or array: uint32 length in bytes, then the entries as given.
  Bytes& sized(const std::string& entries) { return str(entries); }
  const std::string& bytes() const { return out_; }
  std::string record(Opcode op) const { return Bytes().u8(static_cast<uint8_t>(op)).u64(out_.size()).raw(out_).out_; }

 private:
  Bytes& put(uint64_t v, int n) {
    for (int i = 0; i < n; ++i) out_.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
    return *this;
  }
  std::string out_;
};

}  // namespace rigctl::mcap
