// Faults the simulated driver injects into its own rig (issue 7): sensor
// faults on the converted readings, plant faults through QuarterCarPlant's
// hooks, and read stalls that make the loop overrun. Given in the KIND@TIME
// syntax of drivers/sim/fault_spec.hpp (`rigctl run --fault`, the config's
// `faults:`), times in rig time. Resolved and checked at construction; the
// per-tick calls are allocation-, lock- and log-free.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "drivers/sim/sensor_model.hpp"
#include "rt/sample.hpp"
#include "drivers/sim/fault_spec.hpp"

namespace rigctl {

class SimulatedPlant;
class QuarterCarPlant;

class SimFaults {
 public:
  SimFaults() = default;
  // sensors: the driver's sensor specs in input order (rail needs an ADC
  // range). Throws std::invalid_argument naming the spec: a kind that only
  // acts on the wire, an unknown channel, a plant fault this plant has no part for.
  SimFaults(const std::vector<FaultSpec>& specs, const ChannelLayout& layout, const std::vector<SensorSpec>& sensors,
            SimulatedPlant& plant, double period_s, uint64_t seed);

  bool empty() const noexcept { return entries_.empty(); }
  // A new run (SimDriver::start): nothing injected yet.
  void reset() noexcept;
  // Plant faults due by `tick`, applied before the sample of that tick is measured.
  void apply_to_plant(int64_t tick) noexcept;
  // Periods the read of `tick` stalls (an overrun burst), 0 normally.
  int stall_periods(int64_t tick) noexcept;
  // Sensor faults on the readings of `tick`.
  void apply_to_sample(int64_t tick, Sample& sample) noexcept;

  // Off the real-time path: "fault TEXT injected at t = ... s" for each fault
  // injected since the previous call, and the count so far.
  std::vector<std::string> take_new_reports();
  int64_t injected_count() const noexcept;

 private:
  struct Entry {
    FaultSpec spec;
    int64_t start_tick = 0;
    int64_t end_tick = INT64_MAX;  // first tick without the fault
    int channel = -1;
    double rail = 0.0;
    int stalls_done = 0;
    double held = 0.0;
    bool holding = false, plant_applied = false;
  };
  std::vector<Entry> entries_;
  // Tick each entry was first injected at, -1 before; read by take_new_reports().
  std::unique_ptr<std::atomic<int64_t>[]> injected_at_;
  std::vector<bool> reported_;
  QuarterCarPlant* quarter_car_ = nullptr;
  double period_s_ = 0.0025;
  uint64_t seed_ = 0;
  std::mt19937_64 rng_;  // the noise burst's own: the sensors' noise stream stays as without faults

  void mark(std::size_t i, int64_t tick) noexcept;
};

}  // namespace rigctl
