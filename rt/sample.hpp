// The data that crosses the driver boundary on every tick. Plain fixed-size
// structs: they are copied on the real-time path and into the telemetry queue,
// so nothing here may allocate.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace rigctl {

// Enough for the half-car's two-post rig plus simulator truth channels.
inline constexpr std::size_t kMaxInputs = 24;
// Eight valves: two four-posters in one loop (the bench's largest rig).
inline constexpr std::size_t kMaxOutputs = 8;
// Control channels of one loop: each its own feedback, controller, demand
// and output (a two-poster road simulator has two). One per output at most.
inline constexpr std::size_t kMaxChannels = kMaxOutputs;

// One named signal in SI units. Built once at start-up, never on the tick path.
struct ChannelInfo {
  std::string name;  // column name of the run-file spec, e.g. "x_r"
  std::string unit;  // SI unit, e.g. "m", "Pa", "1"
};

struct ChannelLayout {
  std::vector<ChannelInfo> inputs;   // what Driver::read fills, in this order
  std::vector<ChannelInfo> outputs;  // what Driver::write takes, in this order

  // Index of a named input or output; -1 when absent.
  int input_index(const std::string& name) const;
  int output_index(const std::string& name) const;
};

struct Sample {
  int64_t t_ns = 0;     // rig time of acquisition: simulated time, or monotonic time since start
  uint32_t status = 0;  // bit i set: input i is invalid (stale, out of range, not a number)
  // Bit j set: output j's actuator does not follow its command now (e.g. a
  // fieldbus valve outside its active state). What is sent still goes out
  // and is recorded, but a controller must not integrate an error the
  // output cannot act on.
  uint32_t outputs_not_following = 0;
  std::array<double, kMaxInputs> value{};
};

struct Command {
  std::array<double, kMaxOutputs> value{};
};

}  // namespace rigctl
