// Where a tick's compute time goes: the duration of each named step of the
// tick (rt/loop/rig_loop.hpp), their maxima and means over the run, and the
// breakdown of the slowest tick. A long tick under load is otherwise one
// number; with this it says whether the read waited on the I/O thread, a
// detector or controller took long, or the hand-off to the publisher did.
//
// Fixed memory, no clock of its own: the loop stamps the end of each step
// with its clock and this is arithmetic on those stamps, so tests inject them.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

namespace rigctl {

// The tick's steps in the order they run. `kCommands` is the operator queue
// and the automatic sequence; `kHandOff` is the record's push to the publisher.
enum class TickStage : uint8_t { kRead, kCheck, kCommands, kDemand, kControl, kWrite, kHandOff };
inline constexpr std::size_t kTickStageCount = 7;

std::string_view to_string(TickStage s) noexcept;

using StageDurations = std::array<int64_t, kTickStageCount>;  // [ns] per TickStage

struct TickStageSummary {
  int64_t ticks = 0;            // ticks whose stages were recorded
  StageDurations max_ns{};      // each stage's longest, over the run
  std::array<double, kTickStageCount> mean_ns{};
  StageDurations slowest_tick_ns{};  // the stages of the tick with the longest sum
  int64_t slowest_tick = -1;         // that tick's number
};

class TickStageTimes {
 public:
  // The tick numbered `tick` began (woke) at `start_ns`.
  void begin(int64_t tick, int64_t start_ns) noexcept;
  // The step `stage` ended at `end_ns`: it took the time since the previous
  // stamp. A stage not stamped in a tick took no time in it.
  void end(TickStage stage, int64_t end_ns) noexcept;
  // The tick is over: fold its stages into the run's figures.
  void finish() noexcept;

  TickStageSummary summary() const noexcept;

 private:
  int64_t tick_ = 0;
  int64_t last_stamp_ns_ = 0;
  StageDurations current_{};
  StageDurations max_{};
  std::array<double, kTickStageCount> sum_{};
  StageDurations slowest_{};
  int64_t slowest_total_ = -1;
  int64_t slowest_tick_ = -1;
  int64_t ticks_ = 0;
};

}  // namespace rigctl
