// The tests' real clients in Node (tests/node: Foxglove's ws-protocol client,
// @mcap/core), run with the npm packages the NodeClients fixture installed
// into the build folder; and what they need: a free port, their JSON results.
#pragma once

#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "read_file.hpp"

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

// A TCP port on 127.0.0.1 that the OS just had free. Another process could
// take it before the server binds it; the port space is large enough that
// this does not happen between parallel tests in practice.
inline int free_tcp_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = 0;
  socklen_t len = sizeof a;
  if (fd < 0 || ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) != 0) {
    throw std::runtime_error("free_tcp_port: no port");
  }
  ::close(fd);
  return ntohs(a.sin_port);
}

inline nlohmann::json read_json(const std::string& path) { return nlohmann::json::parse(read_file(path)); }

}  // namespace rigctl::test
