#include "rt/tick_stages.hpp"

namespace rigctl {

std::string_view to_string(TickStage s) noexcept {
  switch (s) {
    case TickStage::kRead: return "read";
    case TickStage::kCheck: return "check";
    case TickStage::kCommands: return "commands";
    case TickStage::kDemand: return "demand";
    case TickStage::kControl: return "control";
    case TickStage::kWrite: return "write";
    case TickStage::kHandOff: return "hand_off";
  }
  return "?";
}

void TickStageTimes::begin(int64_t tick, int64_t start_ns) noexcept {
  tick_ = tick;
  last_stamp_ns_ = start_ns;
  current_.fill(0);
}

void TickStageTimes::end(TickStage stage, int64_t end_ns) noexcept {
  current_[static_cast<std::size_t>(stage)] += end_ns - last_stamp_ns_;
  last_stamp_ns_ = end_ns;
}

void TickStageTimes::finish() noexcept {
  int64_t total = 0;
  for (std::size_t i = 0; i < kTickStageCount; ++i) {
    const int64_t d = current_[i];
    if (d > max_[i]) max_[i] = d;
    sum_[i] += static_cast<double>(d);
    total += d;
  }
  if (total > slowest_total_) {
    slowest_total_ = total;
    slowest_ = current_;
    slowest_tick_ = tick_;
  }
  ++ticks_;
}

TickStageSummary TickStageTimes::summary() const noexcept {
  TickStageSummary s;
  s.ticks = ticks_;
  s.max_ns = max_;
  for (std::size_t i = 0; i < kTickStageCount; ++i) s.mean_ns[i] = ticks_ > 0 ? sum_[i] / static_cast<double>(ticks_) : 0.0;
  s.slowest_tick_ns = slowest_;
  s.slowest_tick = slowest_tick_;
  return s;
}

}  // namespace rigctl
