// The simulated rig behind the driver interface: a plant stepped one control
// period per tick, seen through sensor models. Time is the tick count times
// the period, never the wall clock, so a paced run and a --fast run of the
// same config and seed are identical. Injected faults (drivers/sim/sim_faults.hpp)
// act on that same rig time.
#pragma once

#include <atomic>
#include <memory>
#include <random>
#include <vector>

#include "drivers/sim/conditioning_filter.hpp"
#include "drivers/sim/delay_line.hpp"
#include "rt/driver.hpp"
#include "drivers/sim/sensor_model.hpp"
#include "drivers/sim/sim_faults.hpp"
#include "plant/simulated_plant.hpp"
#include "rt/loop_clock.hpp"

namespace rigctl {

class SimDriver final : public Driver {
 public:
  // sensors: one per plant signal, in signals() order (truth channels usually
  // get a default, noise-free SensorSpec). dacs: one per plant command, the
  // output converter's range and resolution (noise ignored). safe_command:
  // outputs on make_safe.
  SimDriver(std::unique_ptr<SimulatedPlant> plant, std::vector<SensorSpec> sensors, std::vector<SensorSpec> dacs,
            double period_s, uint64_t seed, std::vector<double> safe_command);

  const ChannelLayout& layout() const override { return layout_; }
  void start() override;
  bool read(Sample& out) override;
  void write(const Command& command) override;
  void make_safe() noexcept override;
  void stop() override {}
  bool simulated() const override { return true; }
  // The injected faults as they happen, and sim_valve_safe_since_ns: the
  // rig time since which the plant has had the safe command (-1: driven).
  DriverDiagnostics diagnostics() override;

  // Faults to inject, before start(). Throws std::invalid_argument naming a
  // bad one (sim_faults.hpp).
  void set_faults(const std::vector<FaultSpec>& faults);
  // The loop's clock: an overrun fault's read stalls on it, wall time in a
  // paced run, virtual time with --fast (the loop sees the same late tick).
  void set_stall_clock(LoopClock* clock) { stall_clock_ = clock; }

  SimulatedPlant& plant() { return *plant_; }

 private:
  std::unique_ptr<SimulatedPlant> plant_;
  std::vector<SensorSpec> sensor_specs_;
  std::vector<SensorModel> sensors_;
  std::vector<DelayLine> delays_;  // per signal; inactive where the spec has no delay
  std::vector<ConditioningFilter> filters_;  // per signal; inactive where the spec has no filter
  std::vector<SensorModel> dacs_;
  ChannelLayout layout_;
  double period_s_;
  int64_t period_ns_;
  uint64_t seed_;
  std::mt19937_64 rng_;
  std::vector<double> command_;
  std::vector<double> safe_command_;
  std::vector<double> truth_;
  int64_t tick_ = 0;
  bool started_ = false;
  SimFaults faults_;
  LoopClock* stall_clock_ = nullptr;
  std::atomic<int64_t> safe_since_ns_{0};
};

}  // namespace rigctl
