// Foxglove section: what serving the telemetry costs and what clients see.
// The quarter car through `rigctl run`'s own code path at 400 Hz, twice in
// one bench run: without a server, then with the WebSocket server and three
// clients subscribed to every channel (in-process, foxglove/server/client.hpp,
// over loopback). Reported: the end-to-end latency from the publisher
// handing a message on to a client having it (p50, p99, max, all clients and
// channels), and the loop's wake-up latency p99 with the clients against
// without them (goal: latency p99 under 50 ms, wake-up p99 within 10 %).
#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <vector>

#include "foxglove/server/client.hpp"
#include "foxglove/server/server.hpp"
#include "rt/histogram.hpp"
#include "tools/bench/sections.hpp"
#include "tools/common/free_port.hpp"

namespace rigctl::bench {

namespace {

using Clock = std::chrono::steady_clock;
constexpr int kClients = 3;
constexpr double kLatencyGoalS = 0.050;
constexpr double kWakeupGoalRatio = 1.10;

// When each message left the publisher, by channel and time stamp; called
// on the publisher thread before the server's feed.
class PublishClock final : public TelemetryTap {
 public:
  void on_message(const std::string& channel, int64_t utime, const uint8_t*, std::size_t) noexcept override {
    const auto now = Clock::now();
    std::lock_guard<std::mutex> lock(mu_);
    times_.emplace(std::make_pair(channel, static_cast<uint64_t>(utime) * 1000u), now);
  }
  bool published(const std::string& topic, uint64_t log_time_ns, Clock::time_point& at) const {
    std::lock_guard<std::mutex> lock(mu_);
    const auto it = times_.find({topic, log_time_ns});
    if (it == times_.end()) return false;
    at = it->second;
    return true;
  }

 private:
  mutable std::mutex mu_;
  std::map<std::pair<std::string, uint64_t>, Clock::time_point> times_;
};

// Receipt minus publication, over every client's every message.
class LatencyRecorder {
 public:
  explicit LatencyRecorder(const PublishClock& clock) : clock_(clock) {}
  void on_message(const foxglove::ReceivedMessage& m) {
    const auto received = Clock::now();
    Clock::time_point sent;
    std::lock_guard<std::mutex> lock(mu_);
    if (!clock_.published(m.topic, m.log_time_ns, sent)) {
      ++unmatched_;
      return;
    }
    histogram_.record(std::chrono::duration_cast<std::chrono::nanoseconds>(received - sent).count());
  }
  DistributionSummary summary() const {
    std::lock_guard<std::mutex> lock(mu_);
    return histogram_.summary();
  }
  int64_t unmatched() const {
    std::lock_guard<std::mutex> lock(mu_);
    return unmatched_;
  }

 private:
  const PublishClock& clock_;
  mutable std::mutex mu_;
  DurationHistogram histogram_{10'000, 100'000};  // 10 us bins up to 1 s
  int64_t unmatched_ = 0;
};

Json loop_json(const LoopRun& run) {
  Json j = Json::object();
  j["wakeup_latency"] = latency_json(run.timing.wakeup_latency);
  j["overruns"] = run.timing.overruns;
  j["ticks"] = run.timing.ticks;
  return j;
}

}  // namespace

Section foxglove_section() {
  return {"foxglove", "foxglove: WebSocket server, 3 clients on every channel: end-to-end latency, loop wake-up",
          [](Context& ctx) {
            const double seconds = ctx.pick(30.0, 3.0);
            Json j = Json::object();
            j["config"] = ctx.quarter_car_config;
            j["seconds_per_run"] = seconds;
            j["clients"] = kClients;
            j["order"] = "the loop without a server, then with the server and the clients";
            j["latency"] = "publisher hands the message on -> a client has decoded the frame (steady clock, one process)";
            ctx.out << "  " << seconds << " s each, the quarter car at 400 Hz: alone, then serving " << kClients
                    << " clients subscribed to every channel\n";

            const LoopRun alone = run_loop(ctx, seconds, "foxglove-alone");
            j["without_clients"] = loop_json(alone);
            if (ctx.stop.load()) return j;

            const int port = free_loopback_port();
            PublishClock clock;
            LatencyRecorder latency(clock);
            std::vector<std::unique_ptr<foxglove::Client>> clients;
            for (int i = 0; i < kClients; ++i) {
              clients.push_back(std::make_unique<foxglove::Client>(
                  "ws://127.0.0.1:" + std::to_string(port), foxglove::kSubprotocols[i % 2],
                  [&latency](const foxglove::ReceivedMessage& m) { latency.on_message(m); }));
              clients.back()->start();  // retries until the run's server is up
            }
            const LoopRun served = run_loop(ctx, seconds, "foxglove-served", [&](RunOptions& o) {
              o.websocket = WsEndpoint{"127.0.0.1", port};
              o.telemetry_taps.push_back(&clock);
            });
            int64_t received = 0;
            for (auto& c : clients) {
              c->stop();
              received += c->received();
            }
            const DistributionSummary l = latency.summary();
            j["with_clients"] = loop_json(served);
            j["messages_received"] = received;
            j["messages_unmatched"] = latency.unmatched();
            j["end_to_end_latency"] = latency_json(l);
            const double wake_ratio = ratio(static_cast<double>(served.timing.wakeup_latency.p99_ns),
                                            static_cast<double>(alone.timing.wakeup_latency.p99_ns));
            j["wakeup_p99_ratio_with_over_without"] = wake_ratio;
            j["latency_p99_goal_s"] = kLatencyGoalS;
            j["latency_p99_within_goal"] = l.count > 0 && static_cast<double>(l.p99_ns) * 1e-9 < kLatencyGoalS;
            j["wakeup_p99_within_10_percent"] = wake_ratio <= kWakeupGoalRatio;
            const auto line = served.console.find("  foxglove: " + std::to_string(kClients) + " clients");
            if (line != std::string::npos) {
              j["server_report"] = served.console.substr(line + 2, served.console.find('\n', line) - line - 2);
            }

            Table t({"run", "wake-up p50 us", "p99 us", "max us", "overruns"});
            for (const auto& [name, run] : {std::pair<const char*, const LoopRun&>{"without clients", alone},
                                            std::pair<const char*, const LoopRun&>{"with 3 clients", served}}) {
              const auto& w = run.timing.wakeup_latency;
              t.row({name, fmt("%.1f", w.p50_ns / 1e3), fmt("%.1f", w.p99_ns / 1e3), fmt("%.1f", w.max_ns / 1e3),
                     std::to_string(run.timing.overruns)});
            }
            ctx.out << "  loop wake-up latency:\n" << t.text("    ")
                    << "  wake-up p99 with/without clients: " << fmt("%.2f", wake_ratio) << " (goal <= 1.10)\n"
                    << "  end-to-end latency, " << received << " messages to " << kClients
                    << " clients: " << latency_text(l) << " (goal p99 < 50 ms)\n";
            return j;
          }};
}

}  // namespace rigctl::bench
