// CAN: a frame's round trip over the seqpacket transport (CanTransport both
// ends, an echo thread) against bare send/poll/recv on a socketpair.
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <thread>

#include "drivers/canopen/can_transport.hpp"
#include "rt/histogram.hpp"
#include "tools/bench/io_support.hpp"

namespace rigctl::bench::io {

namespace {

// The frames echoed through CanTransport at both ends. `pin` holds the
// calling thread on the server's CPU (the echo thread starts there) and is
// moved to the client's for the sender.
void transport_round_trips(Context& ctx, int64_t frames, int64_t period_ns, int64_t& lost, const Placement& where,
                           std::optional<PinnedScope>& pin, DurationHistogram& hist) {
  auto ends = socketpair_seqpacket();
  CanTransport& a = ends.first;
  CanTransport& b = ends.second;
  std::thread echo([&b] {
    canopen::CanFrame f;
    for (;;) {
      const auto rx = b.receive(f, 200);
      if (rx == CanTransport::Rx::kFrame) {
        b.send(f);
      } else if (rx != CanTransport::Rx::kTimeout) {
        return;
      }
    }
  });
  pin.emplace(where.client_cpu);  // and the sender runs here
  int64_t next = mono_ns();
  for (int64_t k = 0; k < frames && !ctx.stop.load(); ++k) {
    canopen::CanFrame f = canopen::make_frame(0x201, {0x0f, 0x00, static_cast<uint8_t>(k), static_cast<uint8_t>(k >> 8)});
    canopen::CanFrame g;
    const int64_t t0 = mono_ns();
    a.send(f);
    if (a.receive(g, 100) == CanTransport::Rx::kFrame && g.data[2] == f.data[2]) {
      hist.record(mono_ns() - t0);
    } else {
      ++lost;
    }
    next += period_ns;
    sleep_until_ns(next);
  }
  a.shutdown();
  echo.join();
}

// The same frames by bare send/poll/recv on a socketpair: the floor.
void bare_round_trips(Context& ctx, int64_t frames, int64_t period_ns, int64_t& lost, const Placement& where,
                      std::optional<PinnedScope>& pin, DurationHistogram& hist) {
  int sv[2];
  if (::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, sv) != 0) {
    throw std::runtime_error(std::string("socketpair: ") + std::strerror(errno));
  }
  std::thread echo([fd = sv[1]] {
    canopen::CanFrame f;
    pollfd p{fd, POLLIN, 0};
    for (;;) {
      p.revents = 0;
      const int rc = ::poll(&p, 1, 200);
      if (rc < 0 && errno == EINTR) continue;
      if (rc == 0) continue;
      if (rc < 0 || (p.revents & (POLLHUP | POLLERR)) != 0) return;
      const ssize_t n = ::recv(fd, &f, sizeof f, 0);
      if (n <= 0) return;
      ::send(fd, &f, sizeof f, MSG_DONTWAIT | MSG_NOSIGNAL);
    }
  });
  pin.emplace(where.client_cpu);
  int64_t next = mono_ns();
  pollfd p{sv[0], POLLIN, 0};
  for (int64_t k = 0; k < frames && !ctx.stop.load(); ++k) {
    canopen::CanFrame f = canopen::make_frame(0x201, {0x0f, 0x00, static_cast<uint8_t>(k), static_cast<uint8_t>(k >> 8)});
    canopen::CanFrame g;
    const int64_t t0 = mono_ns();
    ::send(sv[0], &f, sizeof f, MSG_DONTWAIT | MSG_NOSIGNAL);
    p.revents = 0;
    if (::poll(&p, 1, 100) == 1 && ::recv(sv[0], &g, sizeof g, 0) == static_cast<ssize_t>(sizeof g) &&
        g.data[2] == f.data[2]) {
      hist.record(mono_ns() - t0);
    } else {
      ++lost;
    }
    next += period_ns;
    sleep_until_ns(next);
  }
  ::shutdown(sv[0], SHUT_RDWR);
  echo.join();
  ::close(sv[0]);
  ::close(sv[1]);
}

DistributionSummary can_round_trips(Context& ctx, bool through_transport, int64_t frames, int64_t period_ns,
                                    int64_t& lost, const Placement& where) {
  DurationHistogram hist(1000, 20000);
  lost = 0;
  std::optional<PinnedScope> pin;
  pin.emplace(where.server_cpu);  // the echo thread starts here
  if (through_transport) {
    transport_round_trips(ctx, frames, period_ns, lost, where, pin, hist);
  } else {
    bare_round_trips(ctx, frames, period_ns, lost, where, pin, hist);
  }
  return hist.summary();
}

}  // namespace

Json can_bench(Context& ctx, Table& table) {
  const int64_t frames = ctx.pick<int64_t>(2000, 200);
  const int64_t period_ns = 2'500'000;
  Json j = Json::object();
  j["what"] = "16-byte struct can_frame sent, echoed by a second thread, received; one frame per 2.5 ms; normal priority";
  j["frames_each"] = frames;
  for (const auto& where : placements()) {
    if (ctx.stop.load()) break;
    int64_t lost_t = 0, lost_b = 0;
    const DistributionSummary t = can_round_trips(ctx, true, frames, period_ns, lost_t, where);
    const DistributionSummary b = can_round_trips(ctx, false, frames, period_ns, lost_b, where);
    Json p = Json::object();
    p["echo_cpu"] = where.server_cpu;
    p["sender_cpu"] = where.client_cpu;
    Json tj = Json::object();
    tj["round_trip"] = latency_json(t);
    tj["lost"] = lost_t;
    p["can_transport"] = tj;
    Json bj = Json::object();
    bj["round_trip"] = latency_json(b);
    bj["lost"] = lost_b;
    p["bare_socketpair"] = bj;
    p["ratio_transport_over_bare"] = comparison_row(t, b);
    table.row(cells("CAN frame round trip, " + where.name, "CanTransport (seqpacket)", t));
    table.row(cells("", "bare socketpair", b));
    ratio_row(table, p["ratio_transport_over_bare"]);
    j[where.name] = p;
  }
  j["status"] = "ok";
  return j;
}

}  // namespace rigctl::bench::io
