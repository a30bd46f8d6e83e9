#include "tools/bench/io_support.hpp"

#include <pthread.h>
#include <sched.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace rigctl::bench::io {

int64_t mono_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

void sleep_until_ns(int64_t t) {
  const timespec ts{static_cast<time_t>(t / 1'000'000'000), static_cast<long>(t % 1'000'000'000)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

std::string set_fifo(int priority) {
  if (priority <= 0) return "normal scheduling";
  sched_param p{};
  p.sched_priority = priority;
  const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p);
  return rc == 0 ? "SCHED_FIFO " + std::to_string(priority) : "best effort (SCHED_FIFO refused: " + std::string(std::strerror(rc)) + ")";
}

Json comparison_row(const DistributionSummary& ours, const DistributionSummary& bare) {
  Json r = Json::object();
  r["p50"] = ratio(static_cast<double>(ours.p50_ns), static_cast<double>(bare.p50_ns));
  r["p99"] = ratio(static_cast<double>(ours.p99_ns), static_cast<double>(bare.p99_ns));
  r["p999"] = ratio(static_cast<double>(ours.p999_ns), static_cast<double>(bare.p999_ns));
  r["max"] = ratio(static_cast<double>(ours.max_ns), static_cast<double>(bare.max_ns));
  return r;
}

std::vector<std::string> cells(const std::string& a, const std::string& b, const DistributionSummary& d) {
  return {a, b, fmt("%.1f", d.p50_ns / 1e3), fmt("%.1f", d.p99_ns / 1e3), fmt("%.1f", d.p999_ns / 1e3),
          fmt("%.1f", d.max_ns / 1e3), std::to_string(d.count)};
}

void ratio_row(Table& table, const Json& r) {
  table.row({"", "ratio", fmt("%.2f", r.find("p50")->number()), fmt("%.2f", r.find("p99")->number()),
             fmt("%.2f", r.find("p999")->number()), fmt("%.2f", r.find("max")->number()), ""});
}

std::vector<Placement> placements() {
  std::vector<Placement> p = {{"same_cpu", 0, 0}};
  if (sysconf(_SC_NPROCESSORS_ONLN) > 1) p.push_back({"cross_cpu", 1, 0});
  return p;
}

}  // namespace rigctl::bench::io
