#include "rt/timing_stats.hpp"

#include <stdexcept>
#include <string>

namespace rigctl {

namespace {
constexpr int64_t kBinNs = 1000;
int bins_for(int64_t period_ns) { return static_cast<int>(2 * period_ns / kBinNs) + 1; }
}  // namespace

std::string_view to_string(OverrunPolicy p) { return p == OverrunPolicy::kSkip ? "skip" : "catch_up"; }

OverrunPolicy overrun_policy_from_string(std::string_view s) {
  if (s == "skip") return OverrunPolicy::kSkip;
  if (s == "catch_up") return OverrunPolicy::kCatchUp;
  throw std::invalid_argument("unknown overrun policy '" + std::string(s) + "' (expected skip or catch_up)");
}

TimingStats::TimingStats(int64_t period_ns, OverrunPolicy policy)
    : period_ns_(period_ns), policy_(policy), latency_(kBinNs, bins_for(period_ns)),
      compute_(kBinNs, bins_for(period_ns)) {
  if (period_ns <= 0) throw std::invalid_argument("loop period must be positive");
}

void TimingStats::on_wake(int64_t deadline_ns, int64_t wake_ns) noexcept {
  latency_.record(wake_ns - deadline_ns);
  stages_.begin(ticks_, wake_ns);
}

int64_t TimingStats::on_done(int64_t deadline_ns, int64_t start_ns, int64_t end_ns) noexcept {
  compute_.record(end_ns - start_ns);
  stages_.finish();
  ++ticks_;
  const int64_t next = deadline_ns + period_ns_;
  if (end_ns <= next) return next;
  ++overruns_;
  if (policy_ == OverrunPolicy::kCatchUp) return next;
  // First grid point after the end of this tick; the ones passed are missed.
  const int64_t periods_late = (end_ns - deadline_ns) / period_ns_;
  missed_ += periods_late;
  return deadline_ns + (periods_late + 1) * period_ns_;
}

TimingSummary TimingStats::summary() const noexcept {
  TimingSummary s;
  s.period_ns = period_ns_;
  s.ticks = ticks_;
  s.overruns = overruns_;
  s.missed_ticks = missed_;
  s.wakeup_latency = latency_.summary();
  s.compute = compute_.summary();
  s.stages = stages_.summary();
  return s;
}

}  // namespace rigctl
