// End-to-end tests on the wire: `rigctl run` with a hardware driver against
// `rigctl rig-sim` (Modbus DAQ on 127.0.0.1, the CANopen valve on a
// seqpacket socket in the test's own folder), with the test config of
// wire_config.hpp. The fixture starts rig-sim and writes configs; the
// helpers read run files and what rig-sim reported of its valve.
// (test_hardware_in_the_loop, test_canopen_valve_run)
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <fstream>
#include <iterator>
#include <memory>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "background_process.hpp"
#include "process.hpp"
#include "read_file.hpp"
#include "wire_config.hpp"

namespace rigctl::test {

inline const std::string kRigctl = RIGCTL_BINARY;
inline const std::string kShippedConfig = std::string(RIGCTL_SOURCE_DIR) + "/config/quarter_car.yaml";

struct RunFile {
  std::vector<std::string> names;
  std::vector<std::vector<double>> rows;
  std::vector<double> column(const std::string& name) const {
    const auto it = std::find(names.begin(), names.end(), name);
    EXPECT_NE(it, names.end()) << name;
    std::vector<double> out;
    if (it == names.end()) return out;
    const auto k = static_cast<std::size_t>(it - names.begin());
    for (const auto& r : rows) out.push_back(r[k]);
    return out;
  }
};

inline RunFile read_run_file(const std::string& path) {
  RunFile f;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::stringstream ss(line);
    std::string cell;
    if (f.names.empty()) {
      while (std::getline(ss, cell, ',')) f.names.push_back(cell);
      continue;
    }
    std::vector<double> row;
    while (std::getline(ss, cell, ',')) row.push_back(std::stod(cell));
    f.rows.push_back(row);
  }
  return f;
}

// Rig time of the last row in a run file.
inline double last_time(const std::string& csv) {
  const auto t = read_run_file(csv).column("t");
  return t.empty() ? -1.0 : t.back();
}

class RigSimTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // The test's name hashed, not spelt out: the valve's socket lives in this
    // folder, and a Unix socket's path has at most 107 characters (a long
    // test name made rig-sim refuse canopen.socket_path).
    const std::string test = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    char hash[17];
    std::snprintf(hash, sizeof hash, "%016zx", std::hash<std::string>{}(test));
    dir_ = std::filesystem::temp_directory_path() / ("rigctl_wire_" + std::to_string(::getpid()) + "_" + hash);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  // The shipped config with another driver line and the test's timing
  // (tests/support/wire_config.hpp).
  std::string write_config(const std::string& driver, int port, double heartbeat_timeout_s = kWireMaxAge) {
    const std::string file = path(driver + ".yaml");
    std::ofstream(file) << wire_config(driver, port, path("valve.sock"), heartbeat_timeout_s);
    return file;
  }

  // Starts rig-sim on a free port; returns the port.
  int start_rig_sim(const std::vector<std::string>& extra) {
    std::vector<std::string> argv{kRigctl, "rig-sim", write_config("sim", 1502), "--modbus", "127.0.0.1:0"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    // A fresh output file per start: waiting on an old one would find the
    // previous instance's port.
    sim_ = std::make_unique<BackgroundProcess>(argv, path("rig-sim-" + std::to_string(++sims_) + ".out"));
    EXPECT_TRUE(sim_->wait_for("modbus listening on", 60.0)) << sim_->output();
    std::smatch m;
    const std::string out = sim_->output();
    if (!std::regex_search(out, m, std::regex("modbus listening on 127\\.0\\.0\\.1:(\\d+)"))) return -1;
    return std::stoi(m[1].str());
  }

  // rig-sim with the CANopen valve on the test's socket: returns the port.
  int start_rig_sim_with_valve(const std::vector<std::string>& extra) {
    std::vector<std::string> argv{"--can-socket", path("valve.sock")};
    argv.insert(argv.end(), extra.begin(), extra.end());
    const int port = start_rig_sim(argv);
    EXPECT_TRUE(sim_->wait_for("canopen valve on", 60.0)) << sim_->output();
    return port;
  }

  std::unique_ptr<BackgroundProcess> sim_;
  int sims_ = 0;
  std::filesystem::path dir_;
};

inline const std::regex kValveReport("rig-sim: t = ([0-9.]+) s, valve u = ([-0-9.e]+)");

// The valve commands rig-sim reported after time t (its own clock).
inline std::vector<double> valve_commands_after(const std::string& sim_output, double t) {
  std::vector<double> out;
  for (auto it = std::sregex_iterator(sim_output.begin(), sim_output.end(), kValveReport); it != std::sregex_iterator();
       ++it) {
    if (std::stod((*it)[1].str()) > t) out.push_back(std::stod((*it)[2].str()));
  }
  return out;
}

// Call when the run has ended: waits until rig-sim has reported its valve
// twice more (it does twice a second), however long a loaded machine takes,
// then returns the commands it reported after time t. Waiting for the
// reports, not sleeping, is what makes "it stays at null" cover time after
// the run whatever the scheduler does.
inline std::vector<double> valve_commands_after_the_run(BackgroundProcess& sim, double t) {
  const std::size_t run_ended = sim.output().size();
  const bool reported = sim.wait_until(
      [&](const std::string& out) {
        if (out.size() <= run_ended) return false;
        const std::string later = out.substr(run_ended);
        const auto reports = std::sregex_iterator(later.begin(), later.end(), kValveReport);
        return std::distance(reports, std::sregex_iterator()) >= 2;
      },
      60.0);
  EXPECT_TRUE(reported) << "rig-sim stopped reporting its valve\n" << sim.output();
  return valve_commands_after(sim.output(), t);
}

}  // namespace rigctl::test
