// What the I/O benchmarks share: the monotonic clock and absolute sleeps
// they pace with, the scheduling they ask for, where their two ends run,
// and the rows that compare a rigctl path with the bare client.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "tools/bench/sections.hpp"

namespace rigctl::bench::io {

int64_t mono_ns();
void sleep_until_ns(int64_t t);
// SCHED_FIFO at `priority` for the calling thread (0 or less: leave it); says what it got.
std::string set_fifo(int priority);

// Ratios ours / bare at p50, p99, p99.9 and max.
Json comparison_row(const DistributionSummary& ours, const DistributionSummary& bare);
std::vector<std::string> cells(const std::string& a, const std::string& b, const DistributionSummary& d);
void ratio_row(Table& table, const Json& r);

// Where the threads run: a loopback round trip is two thread wake-ups, and
// on this kind of VM a wake-up on the other CPU costs tens of microseconds,
// so unpinned runs mix two distributions at random. Each comparison is made
// with both ends on one CPU and with them on different CPUs.
struct Placement {
  std::string name;
  int server_cpu;
  int client_cpu;
};

std::vector<Placement> placements();

// The section's three parts, each filling its table and returning its JSON.
Json modbus_bench(Context& ctx, Table& table);
Json can_bench(Context& ctx, Table& table);
Json lcm_bench(Context& ctx, Table& lcm_table);

}  // namespace rigctl::bench::io
