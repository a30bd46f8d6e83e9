// Foxglove limits section: what a full house of clients and a hostile one
// cost the loop. The quarter car through `rigctl run`'s own code path at
// 400 Hz, three times in one bench run: without clients; with the server's
// client limit reached (16 listening clients on every channel, a 17th
// retrying every 50 ms and refused with HTTP 503); and with 15 listening
// clients and one flooding requests without reading its answers (the
// limit again: closed by the server when its queue is full, it connects
// again at once, and is refused while its old slot is still closing). Reported per run: the loop's wake-up and
// compute p99, overruns, and the server's refusals.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "foxglove/server/client.hpp"
#include "foxglove/server/server.hpp"
#include "tools/bench/sections.hpp"
#include "tools/common/free_port.hpp"

namespace rigctl::bench {

namespace {

constexpr int kMaxClients = 16;  // the server's default (telemetry.websocket.max_clients)

// A client that upgrades by hand, then writes getParameters requests as
// fast as the socket takes them and never reads; when the server closes
// it, it connects again.
class Flooder {
 public:
  explicit Flooder(int port) : port_(port) {
    thread_ = std::thread([this] {
      while (!stop_.load()) flood_once();
    });
  }
  ~Flooder() {
    stop_.store(true);
    thread_.join();
  }
  int64_t connections() const { return connections_.load(); }
  int64_t requests() const { return requests_.load(); }
  int64_t refused() const { return refused_.load(); }

 private:
  void flood_once() {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<uint16_t>(port_));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    timeval timeout{0, 200'000};  // a blocked write or read gives stop() a chance
    ::setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &timeout, sizeof timeout);
    ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
      ::close(fd);
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      return;
    }
    const std::string upgrade = "GET / HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port_) +
                                "\r\nUpgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Key: MDEyMzQ1Njc4OWFiY2RlZg==\r\n"
                                "Sec-WebSocket-Version: 13\r\nSec-WebSocket-Protocol: foxglove.websocket.v1\r\n\r\n";
    if (::write(fd, upgrade.data(), upgrade.size()) <= 0 || !upgraded(fd)) {
      ::close(fd);  // refused (503 while the other clients fill every slot): knock again a little later
      ++refused_;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      return;
    }
    ++connections_;
    // One masked text frame (mask 0: the payload as is), sent again and again.
    const std::string body = R"({"op":"getParameters","id":"flood"})";
    std::string frame = {static_cast<char>(0x81), static_cast<char>(0x80 | body.size()), 0, 0, 0, 0};
    frame += body;
    std::string burst;
    for (int i = 0; i < 64; ++i) burst += frame;
    while (!stop_.load()) {
      const ssize_t n = ::send(fd, burst.data(), burst.size(), MSG_NOSIGNAL);
      if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) continue;
      if (n <= 0) break;  // closed by the server
      requests_ += n / static_cast<ssize_t>(frame.size());
    }
    ::close(fd);
  }

  // The handshake's answer, read up to its blank line: the only bytes the flooder reads.
  static bool upgraded(int fd) {
    std::string head;
    char c = 0;
    while (head.size() < 4096 && head.find("\r\n\r\n") == std::string::npos && ::read(fd, &c, 1) == 1) head.push_back(c);
    return head.rfind("HTTP/1.1 101", 0) == 0;
  }

  int port_;
  std::atomic<int64_t> refused_{0};
  std::atomic<bool> stop_{false};
  std::atomic<int64_t> connections_{0};
  std::atomic<int64_t> requests_{0};
  std::thread thread_;
};

std::vector<std::unique_ptr<foxglove::Client>> listeners(int port, int n) {
  std::vector<std::unique_ptr<foxglove::Client>> out;
  for (int i = 0; i < n; ++i) {
    out.push_back(std::make_unique<foxglove::Client>("ws://127.0.0.1:" + std::to_string(port), foxglove::kSubprotocols[i % 2],
                                                     [](const foxglove::ReceivedMessage&) {}));
    out.back()->start();  // retries every 50 ms until connected: the one past the limit keeps knocking
  }
  return out;
}

// The run's closing "foxglove: N clients, ..." report line (clients, sent, dropped, refusals).
std::string server_report(const LoopRun& run) {
  std::istringstream in(run.console);
  for (std::string line; std::getline(in, line);) {
    if (line.find("foxglove: ") != std::string::npos && line.find(" clients, ") != std::string::npos) return line.substr(line.find("foxglove: "));
  }
  return "";
}

Json run_json(const LoopRun& run, int64_t received) {
  Json j = Json::object();
  j["wakeup_latency"] = latency_json(run.timing.wakeup_latency);
  j["compute"] = latency_json(run.timing.compute);
  j["overruns"] = run.timing.overruns;
  j["ticks"] = run.timing.ticks;
  j["messages_received"] = received;
  j["server_report"] = server_report(run);
  return j;
}

LoopRun served_run(Context& ctx, double seconds, const std::string& tag, int port, int listening, bool flood,
                   int64_t& received, Json& extra) {
  // Without the flooder a 17th knocks past the limit; with it, the 16th
  // slot is the flooder's (a listener retrying every 50 ms would take it
  // from the flooder each time the server closes it).
  auto clients = listeners(port, flood ? listening : listening + 1);
  std::unique_ptr<Flooder> flooder;
  const LoopRun run = run_loop(ctx, seconds, tag, [&](RunOptions& o) {
    o.websocket = WsEndpoint{"127.0.0.1", port};
    if (flood) flooder = std::make_unique<Flooder>(port);
  });
  if (flooder) {
    extra["flood_connections"] = flooder->connections();
    extra["flood_refused"] = flooder->refused();
    extra["flood_requests_written"] = flooder->requests();
    flooder.reset();
  }
  received = 0;
  for (auto& c : clients) {
    c->stop();
    received += c->received();
  }
  return run;
}

}  // namespace

Section foxglove_limits_section() {
  return {"foxglove_limits", "foxglove limits: no clients / 16 clients (the limit) and a 17th refused / 15 clients and a flooder (the limit)",
          [](Context& ctx) {
            const double seconds = ctx.pick(30.0, 3.0);
            Json j = Json::object();
            j["config"] = ctx.quarter_car_config;
            j["seconds_per_run"] = seconds;
            j["max_clients"] = kMaxClients;
            ctx.out << "  " << seconds << " s each, the quarter car at 400 Hz\n";
            const LoopRun alone = run_loop(ctx, seconds, "limits-alone");
            j["without_clients"] = run_json(alone, 0);
            if (ctx.stop.load()) return j;

            int64_t received_full = 0, received_flood = 0;
            Json full_extra = Json::object(), flood_extra = Json::object();
            const LoopRun full = served_run(ctx, seconds, "limits-full", free_loopback_port(), kMaxClients, false,
                                            received_full, full_extra);
            j["limit_reached"] = run_json(full, received_full);
            if (ctx.stop.load()) return j;
            const LoopRun flooded = served_run(ctx, seconds, "limits-flood", free_loopback_port(), kMaxClients - 1, true,
                                               received_flood, flood_extra);
            j["limit_reached_and_flooder"] = run_json(flooded, received_flood);
            j["limit_reached_and_flooder"]["flood_connections"] = flood_extra["flood_connections"];
            j["limit_reached_and_flooder"]["flood_requests_written"] = flood_extra["flood_requests_written"];
            j["limit_reached_and_flooder"]["flood_refused"] = flood_extra["flood_refused"];

            Table t({"run", "wake-up p99 us", "compute p99 us", "overruns", "messages to clients"});
            const std::pair<const char*, const LoopRun*> rows[] = {
                {"no clients", &alone}, {"16 clients + 1 refused", &full}, {"15 clients + flooder", &flooded}};
            const int64_t received[] = {0, received_full, received_flood};
            for (int i = 0; i < 3; ++i) {
              const auto& r = *rows[i].second;
              t.row({rows[i].first, fmt("%.1f", r.timing.wakeup_latency.p99_ns / 1e3), fmt("%.1f", r.timing.compute.p99_ns / 1e3),
                     std::to_string(r.timing.overruns), std::to_string(received[i])});
            }
            ctx.out << t.text("    ") << "  " << server_report(full) << "\n  " << server_report(flooded) << "\n"
                    << "  flooder: " << fmt("%.0f", flood_extra["flood_connections"].number()) << " connections closed by the server, "
                    << fmt("%.0f", flood_extra["flood_refused"].number()) << " upgrades refused, "
                    << fmt("%.0f", flood_extra["flood_requests_written"].number()) << " requests written\n";
            return j;
          }};
}

}  // namespace rigctl::bench
