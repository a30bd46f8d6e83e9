// What the drive-iteration system tests share: the shipped quarter car's
// config, a fresh folder per test, `rigctl` run as a command, and the
// summary.json an iteration writes.
#pragma once

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <string>

#include "process.hpp"

namespace rigctl::test {

inline const std::string kQuarterCarConfig = std::string(RIGCTL_SOURCE_DIR) + "/config/quarter_car.yaml";

// An empty folder under the test's temp dir, named prefix-name.
inline std::string fresh_dir(const std::string& prefix, const std::string& name) {
  const auto dir = std::filesystem::path(::testing::TempDir()) / (prefix + "-" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

inline ProcessResult rigctl(const std::string& args) { return run_command(std::string(RIGCTL_BINARY) + " " + args); }

inline nlohmann::json summary_of(const std::string& out_dir) {
  std::ifstream f(out_dir + "/summary.json");
  EXPECT_TRUE(f.good()) << "no summary.json in " << out_dir;
  return nlohmann::json::parse(f);
}

}  // namespace rigctl::test
