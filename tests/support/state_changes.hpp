// "from -> to" of every state_changed line of a run's event log, in file
// order: what the end-to-end tests compare against the sequence they drove.
#pragma once

#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace rigctl::test {

inline std::vector<std::string> state_changes(const std::string& events) {
  std::vector<std::string> out;
  const std::regex re("code=state_changed .*message=\"([a-z_]+ -> [a-z_]+)\"");
  std::istringstream in(events);
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    if (std::regex_search(line, m, re)) out.push_back(m[1]);
  }
  return out;
}

}  // namespace rigctl::test
