// Fuzzes the config loader (config/config_reader.cpp, config/rig_config.cpp and
// the section readers) through parse_rig_config(), the load-from-string entry
// point: the input is a YAML file's text. ConfigError is the loader's
// documented answer to a bad file; any other exception, a crash or a
// sanitizer report is a bug. Files with `cases:` are also loaded with one case
// applied (a name from the shipped configs, or one no file defines), and
// every 8th input size is also written to a file for config_case_names().
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <unistd.h>

#include "config/config_reader.hpp"
#include "config/rig_config.hpp"

namespace {

// Case names to apply: those of the shipped config/*.yaml (read at start
// with config_case_names) and one no file defines.
std::vector<std::string>& case_names() {
  static std::vector<std::string> names;
  return names;
}

void parse(const std::string& text, const std::string& case_name) {
  try {
    const rigctl::RigConfig c = rigctl::parse_rig_config(text, "fuzz.yaml", case_name);
    (void)c;
  } catch (const rigctl::ConfigError& e) {
    if (std::getenv("FUZZ_VERBOSE")) std::fprintf(stderr, "case '%s': %s\n", case_name.c_str(), e.what());
    return;
  }
  if (std::getenv("FUZZ_VERBOSE")) std::fprintf(stderr, "case '%s': accepted\n", case_name.c_str());
}

// The path-based entry point, config_case_names(), reads this file.
const std::string& temp_path() {
  static const std::string path =
      (std::filesystem::temp_directory_path() / ("rigctl-fuzz_config-" + std::to_string(getpid()) + ".yaml")).string();
  return path;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  std::atexit([] { std::remove(temp_path().c_str()); });
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(RIGCTL_SOURCE_DIR "/config", ec)) {
    if (entry.path().extension() != ".yaml") continue;
    try {
      for (const auto& name : rigctl::config_case_names(entry.path().string())) case_names().push_back(name);
    } catch (const rigctl::ConfigError&) {
    }
  }
  std::sort(case_names().begin(), case_names().end());
  case_names().push_back("no_such_case");
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  parse(text, "");
  // A YAML parse costs milliseconds: apply a case only to files that have
  // `cases`, and one case (picked by the size) per input.
  if (text.find("cases") != std::string::npos) parse(text, case_names()[size % case_names().size()]);
  // Every 8th input size also goes through a file and config_case_names().
  if (size % 8 == 0) {
    if (FILE* f = std::fopen(temp_path().c_str(), "wb")) {
      std::fwrite(data, 1, size, f);
      std::fclose(f);
      try {
        (void)rigctl::config_case_names(temp_path());
      } catch (const rigctl::ConfigError&) {
      }
    }
  }
  return 0;
}
