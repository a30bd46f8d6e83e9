// The FRF file (JSON, docs/frf-files.md): written by `rigctl identify`,
// read by `rigctl tune` and the drive iteration.
#pragma once

#include <stdexcept>
#include <string>

#include "tools/identify/frf_data.hpp"

namespace rigctl {

class FrfFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

inline constexpr int kFrfFormatVersion = 1;

std::string frf_to_json(const FrfData& frf);
void write_frf_file(const FrfData& frf, const std::string& path);

// Throws FrfFileError naming the file and the missing or bad key.
FrfData parse_frf_json(const std::string& text, const std::string& name);
FrfData read_frf_file(const std::string& path);

}  // namespace rigctl
