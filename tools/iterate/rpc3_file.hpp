// RPC III time-history files (.rsp responses, .drv drives, .tim time
// histories), the files road-simulator users exchange (MTS RPC, and what
// Siemens and Schenck tools import). The format, as rigctl reads and writes
// it (docs/drive-iteration.md 5):
//  * a header of 512-byte blocks, each four 128-byte records: a keyword of
//    32 bytes and its value of 96, ASCII, NUL-padded; FORMAT,
//    NUM_HEADER_BLOCKS and NUM_PARAMS are the first three records;
//  * the data after the header, in groups: each group holds PTS_PER_GROUP
//    points of channel 1, then of channel 2, ...; the last group is padded;
//  * SHORT_INTEGER data (16-bit) times SCALE.CHAN_n are the values in
//    UNITS.CHAN_n; FLOATING_POINT data (32-bit IEEE) are the values.
// Only little-endian binary files (FORMAT BINARY or BINARY_IEEE_LITTLE_END)
// are read; the rest is refused by name.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace rigctl {

class Rpc3Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class Rpc3DataType { kShortInteger, kFloatingPoint };

struct Rpc3Channel {
  std::string name;  // DESC.CHAN_n
  std::string unit;  // UNITS.CHAN_n
  std::vector<double> values;
};

struct Rpc3File {
  std::string time_type = "RESPONSE";  // TIME_TYPE: RESPONSE, DRIVE, ...
  double period_s = 0.0;               // DELTA_T
  std::vector<Rpc3Channel> channels;

  // The channel named `name`; throws Rpc3Error naming `file` and the channels it has.
  const std::vector<double>& channel(const std::string& name, const std::string& file) const;
};

// .rsp, .drv, .tim, .rpc (any case).
bool is_rpc3_path(const std::string& path);
// The time type a file's extension stands for: .drv DRIVE, else RESPONSE.
std::string rpc3_time_type_for(const std::string& path);

Rpc3File parse_rpc3(const std::string& bytes, const std::string& name);
Rpc3File read_rpc3_file(const std::string& path);
std::string rpc3_bytes(const Rpc3File& file, Rpc3DataType type);
void write_rpc3_file(const Rpc3File& file, const std::string& path, Rpc3DataType type = Rpc3DataType::kShortInteger);

}  // namespace rigctl
