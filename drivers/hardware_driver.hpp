// The physical rig's driver: sensors (and, for a rig without a fieldbus
// valve, the valve's analogue output) on a Modbus DAQ, and optionally the
// servovalve on CANopen. It composes the two I/O parts behind the driver
// interface; each keeps its own I/O thread, so the loop only ever copies the
// newest sample and posts the newest command.
#pragma once

#include <memory>
#include <optional>

#include "drivers/canopen/canopen_valve.hpp"
#include "rt/driver.hpp"
#include "drivers/modbus/modbus_daq.hpp"

namespace rigctl {

class HardwareDriver final : public Driver {
 public:
  // first_sample_timeout_s bounds start(): the DAQ must deliver a complete
  // sample and the valve reach operational in that time.
  HardwareDriver(ModbusDaqConfig daq, std::optional<CanopenValveConfig> valve, double first_sample_timeout_s);
  ~HardwareDriver() override;

  const ChannelLayout& layout() const override { return layout_; }
  void start() override;
  bool read(Sample& out) override;
  void write(const Command& command) override;
  void make_safe() noexcept override;
  void stop() override;
  DriverDiagnostics diagnostics() override;
  std::string input_fault_cause(std::size_t input) const override;
  DistributionSummary io_latency() const override { return daq_->io_latency(); }

 private:
  std::unique_ptr<ModbusDaq> daq_;
  std::unique_ptr<CanopenValve> valve_;
  ChannelLayout layout_;
  double first_sample_timeout_s_;
  std::size_t daq_inputs_ = 0;
  std::size_t daq_outputs_ = 0;
  std::size_t valve_output_ = 0;  // index of the valve setpoint among the outputs
  int64_t start_ns_ = 0;
  int64_t max_output_age_ns_ = 0;
  int64_t lock_step_reads_ = 0;  // reads since start(), in lock-step
};

}  // namespace rigctl
