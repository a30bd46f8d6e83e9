// A listening Foxglove WebSocket client: connects (retrying until the server
// is up), subscribes to every channel the server advertises and hands each
// message to a callback on the client's thread. For `rigctl bench`, which
// measures what clients see; rigctl's tests use Foxglove's own client.
// Plain C++17 like server.hpp: only client.cpp sees websocketpp.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

namespace rigctl::foxglove {

struct ReceivedMessage {
  const std::string& topic;
  uint64_t log_time_ns;
  const char* payload;
  std::size_t size;
};

class Client {
 public:
  Client(std::string url, std::string subprotocol, std::function<void(const ReceivedMessage&)> on_message);
  ~Client();
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  void start();  // the client's thread: connect, retrying every 50 ms until stop()
  void stop();

  bool connected() const;
  int64_t received() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rigctl::foxglove
