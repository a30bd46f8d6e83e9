// A Foxglove WebSocket protocol server (docs/foxglove.md): channels with JSON
// schemas and JSON messages, status messages with ids, read-only parameters.
// It knows nothing of rigs: the telemetry feed (foxglove/telemetry) decides
// what is published. Parameters cannot be set. Clients may publish only
// when a ClientPublishHandler is set, and only on the topics it names (the
// operator console's commands, foxglove/console); plain HTTP GETs on the same
// port are answered by the HttpHandler when one is set (the console's page).
//
// Threads: publish(), add_channel(), set_status() and remove_status() may be
// called from any thread and never wait for a client: each client has one
// bounded queue for everything it is sent (client_queue.hpp: the oldest data
// dropped when full, a client that does not read its answers closed); the
// server's own thread moves messages from the queues onto the sockets while
// the socket keeps up.
//
// Hostile and careless clients (docs/foxglove.md, "Limits"): at most
// max_clients WebSocket clients (the next gets HTTP 503), upgrades and pages
// only for the server's own Host and Origin or the allowed origins (else
// 403), messages of at most kMaxMessageBytes, clients that answer no ping
// for client_timeout_s closed; each refusal counted and reported.
//
// This header is plain C++17 and includes no WebSocket library: websocketpp
// 0.8 does not compile as C++20, so only server.cpp sees it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "foxglove/server/refusal_log.hpp"

namespace rigctl::foxglove {

// The protocol's subprotocol names: clients of different generations ask for
// one or the other, and the protocol is the same.
inline constexpr const char* kSubprotocols[] = {"foxglove.websocket.v1", "foxglove.sdk.v1"};

struct ServerOptions {
  std::string address = "127.0.0.1";  // loopback unless the operator says otherwise
  uint16_t port = 8765;               // 0: any free port (port() tells which)
  // A client's queue in messages. 1024 is 0.85 s of telemetry at 400 Hz
  // (sample, command and controller each tick: 1200 a second, plus the
  // timing and state messages): a client further behind than that is shown fresh data rather
  // than an ever older backlog (and the server's memory stays bounded).
  std::size_t client_queue_messages = 1024;
  // At most this many WebSocket clients at once; the next upgrade is refused
  // with HTTP 503. 16: a control room's consoles and viewers with room,
  // while 16 full queues (kMaxClientQueueBytes each) stay within 32 MiB.
  std::size_t max_clients = 16;
  // Origins (scheme://host[:port]) whose pages may connect besides the
  // server's own, e.g. a reverse proxy's "https://rig1.lab.example"; their
  // hosts are also accepted in the Host header.
  std::vector<std::string> allowed_origins;
  // A ping to every client this often; one that has answered none for
  // client_timeout_s is closed (a vanished peer, a frame sent a byte a
  // second, a client that stopped reading).
  double ping_interval_s = 1.0;
  double client_timeout_s = 10.0;
  std::string name = "rigctl";
  std::map<std::string, std::string> metadata;  // serverInfo.metadata
};

enum class StatusLevel { kInfo = 0, kWarning = 1, kError = 2 };

struct Parameter {
  std::string name;
  double value = 0.0;
};

struct ClientStats {
  std::string address;     // peer address:port
  std::string subprotocol;
  int64_t sent = 0;        // messages written to the socket
  int64_t dropped = 0;     // messages the client's full queue dropped (oldest first)
};

struct ServerStats {
  int64_t clients = 0;     // WebSocket clients so far
  int64_t sent = 0;
  int64_t dropped = 0;
  // The clients connected now and the last kClosedClientsKept that closed,
  // in order of connection (the totals above count every client).
  std::vector<ClientStats> per_client;
  std::map<std::string, int64_t> refusals;  // per kind (RefusalLog's codes)
};

// Messages a client may send: commands and requests are small, and a
// subscribe to every channel is a few kB. Larger messages close the
// connection (1009 message too big) before they are buffered.
inline constexpr std::size_t kMaxMessageBytes = 64 * 1024;
// All a client's queued messages together: a client that falls behind
// loses its oldest data before this; one whose unread answers reach it is closed.
inline constexpr std::size_t kMaxClientQueueBytes = 2 * 1024 * 1024;
// Closed clients whose statistics are kept for the run's report.
inline constexpr std::size_t kClosedClientsKept = 32;

// An HTTP request on the WebSocket port that is not an upgrade.
struct HttpResponse {
  int status = 200;
  std::string content_type = "text/plain; charset=utf-8";
  std::string body;
};
// Called on the server's thread with the path of a GET (query removed).
using HttpHandler = std::function<HttpResponse(const std::string& path)>;

// Messages clients publish on a channel they advertised (capability
// clientPublish). Called on the server's thread; must not throw.
class ClientPublishHandler {
 public:
  virtual ~ClientPublishHandler() = default;
  // `client`: the server's id of the connection (ids are never reused).
  virtual void on_client_message(uint64_t client, const std::string& topic, const std::string& payload) = 0;
  // The connection is gone (closed, failed or the server stopped).
  virtual void on_client_closed(uint64_t client) = 0;
  // The client has answered no ping for `silent_s` seconds (called every
  // ping interval while it is more than one interval).
  virtual void on_client_silent(uint64_t /*client*/, double /*silent_s*/) {}
};

class Sessions;

class Server {
 public:
  // Binds and listens; throws std::runtime_error naming address and port.
  explicit Server(ServerOptions options);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  void start();  // the server's thread
  void stop();   // closes every connection, joins the thread (the destructor calls it)

  uint16_t port() const;
  const std::string& address() const;

  // Before start(): plain HTTP GETs are answered by `handler` (without one,
  // websocketpp's "426 Upgrade Required").
  void set_http_handler(HttpHandler handler);
  // Before start(): offer clientPublish for these topics (JSON encoding)
  // only; advertisements of any other topic are refused with a status.
  void accept_client_publish(ClientPublishHandler* handler, std::vector<std::string> topics);
  // Before start(): where the refusals go besides their counters (the run's
  // event log), rate-limited.
  void set_refusal_handler(RefusalHandler handler);

  // A channel of JSON messages with a JSON schema (schema encoding
  // "jsonschema"); advertised to every client now and to each new one.
  uint32_t add_channel(const std::string& topic, const std::string& schema_name, const std::string& schema);
  bool has_subscribers(uint32_t channel) const;
  // Queues the message for every client subscribed to the channel.
  void publish(uint32_t channel, uint64_t log_time_ns, std::shared_ptr<const std::string> json);
  // Queues the message for one client, if it is connected and subscribed.
  void publish_to(uint64_t client, uint32_t channel, uint64_t log_time_ns, std::shared_ptr<const std::string> json);

  // A status with an id stays active (and is sent to clients that connect
  // later) until remove_status() sends removeStatus for it.
  void set_status(const std::string& id, StatusLevel level, const std::string& message);
  void remove_status(const std::string& id);

  // Answered to getParameters; setParameters is refused (read-only).
  void set_parameters(std::vector<Parameter> parameters);

  ServerStats stats() const;
  // The protocol side (sessions.hpp): what the console's gateway talks to.
  Sessions& sessions();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rigctl::foxglove
