// Config-error tests: a shipped config with one line edited must be refused
// with a message naming the field. Shared by the rig-config tests, and the
// edits the end-to-end tests make to a shipped config.
#pragma once

#include <gtest/gtest.h>

#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "config/config_reader.hpp"
#include "config/rig_config.hpp"
#include "read_file.hpp"
#include "tools/run/rig_assembly.hpp"

namespace rigctl::test {

// config/<name> of the source tree as text.
inline std::string shipped_config(const std::string& name = "quarter_car.yaml") {
  return read_file(std::string(RIGCTL_SOURCE_DIR) + "/config/" + name);
}

// Replaces the first match of `pattern` (a regex); the pattern must match.
inline std::string edit(const std::string& text, const std::string& pattern, const std::string& replacement) {
  const std::regex re(pattern);
  std::string out = std::regex_replace(text, re, replacement, std::regex_constants::format_first_only);
  EXPECT_NE(out, text) << "pattern not found: " << pattern;
  return out;
}

// The quarter car's config for a paced run at normal priority
// (--no-realtime) on a loaded machine: the overrun-burst detector indicates
// instead of stopping the rig. Such a loop is late whenever the scheduler
// runs something else, and a controlled stop for that would end a run whose
// test is about something else. The stop itself is tested where rig time is
// simulated (test_fault_matrix's OverrunBurstStopsTheRigUnderControl).
inline std::string without_overrun_stop(const std::string& text) {
  return edit(text, "(overrun_burst: \\{[^}]*action: )stop\\}", "$1indicate}");
}

// 1-based number of the first line of `text` containing `fragment`, 0 for none.
inline int line_of(const std::string& text, const std::string& fragment) {
  std::istringstream lines(text);
  std::string line;
  for (int n = 1; std::getline(lines, line); ++n) {
    if (line.find(fragment) != std::string::npos) return n;
  }
  return 0;
}

// The ConfigError that loading and assembling `yaml` gives, "" when accepted.
inline std::string config_error_of(const std::string& yaml) {
  try {
    assemble_rig(parse_rig_config(yaml, "bad.yaml"));
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

inline void expect_config_error(const std::string& yaml, const std::vector<std::string>& fragments) {
  const std::string e = config_error_of(yaml);
  ASSERT_FALSE(e.empty()) << "config was accepted";
  for (const auto& f : fragments) EXPECT_NE(e.find(f), std::string::npos) << "'" << f << "' not in: " << e;
}

}  // namespace rigctl::test
