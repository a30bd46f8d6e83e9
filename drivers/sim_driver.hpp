// The simulated rig behind the driver interface: a plant stepped one control
// period per tick, seen through sensor models. Time is the tick count times
// the period, never the wall clock, so a paced run and a --fast run of the
// same config and seed are identical.
#pragma once

#include <memory>
#include <random>
#include <vector>

#include "drivers/delay_line.hpp"
#include "drivers/driver.hpp"
#include "drivers/sensor_model.hpp"
#include "plant/simulated_plant.hpp"

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

  SimulatedPlant& plant() { return *plant_; }

 private:
  std::unique_ptr<SimulatedPlant> plant_;
  std::vector<SensorModel> sensors_;
  std::vector<DelayLine> delays_;  // per signal; inactive where the spec has no delay
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
};

}  // namespace rigctl
