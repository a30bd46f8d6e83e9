// The tests' real clients in Node (tests/node: Foxglove's ws-protocol client,
// @mcap/core), run with the npm packages the NodeClients fixture installed
// into the build folder; and what they need: a free port, their JSON results.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "read_file.hpp"
#include "tools/common/free_port.hpp"

namespace rigctl::test {

// argv for BackgroundProcess: env NODE_PATH=... node tests/node/SCRIPT ARGS...
inline std::vector<std::string> node_argv(const std::string& script, const std::vector<std::string>& args,
                                          const std::vector<std::string>& prefix = {}) {
  std::vector<std::string> argv = prefix;
  argv.insert(argv.end(), {"/usr/bin/env", "NODE_PATH=" + std::string(RIGCTL_BUILD_DIR) + "/node_clients/node_modules",
                           "node", std::string(RIGCTL_SOURCE_DIR) + "/tests/node/" + script});
  argv.insert(argv.end(), args.begin(), args.end());
  return argv;
}

// The same as one shell command line (for run_command).
inline std::string node_command(const std::string& script, const std::vector<std::string>& args) {
  std::string command;
  for (const auto& a : node_argv(script, args)) command += (command.empty() ? "" : " ") + ("'" + a + "'");
  return command;
}

// A port for a server a test starts: the program's own free_loopback_port.
inline int free_tcp_port() { return rigctl::free_loopback_port(); }

inline nlohmann::json read_json(const std::string& path) { return nlohmann::json::parse(read_file(path)); }

}  // namespace rigctl::test
