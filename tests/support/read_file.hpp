// A whole text file as a string ("" when it cannot be read): what the
// end-to-end tests read back (program output, logs, reports).
#pragma once

#include <fstream>
#include <sstream>
#include <string>

namespace rigctl::test {

inline std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace rigctl::test
