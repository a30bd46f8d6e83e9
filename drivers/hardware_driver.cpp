#include "drivers/hardware_driver.hpp"

#include <stdexcept>

namespace rigctl {

HardwareDriver::HardwareDriver(ModbusDaqConfig daq, std::optional<CanopenValveConfig> valve,
                               double first_sample_timeout_s)
    : first_sample_timeout_s_(first_sample_timeout_s) {
  // With the valve on CANopen, the DAQ's analogue valve output (if the
  // config keeps one for `driver: modbus`) is not driven: one config serves
  // both drivers by changing the driver line only.
  if (valve) {
    std::erase_if(daq.outputs, [&](const ModbusChannel& c) { return c.name == valve->setpoint_output; });
  }
  for (const auto& c : daq.inputs) layout_.inputs.push_back({c.name, c.unit});
  for (const auto& c : daq.outputs) layout_.outputs.push_back({c.name, c.unit});
  daq_inputs_ = layout_.inputs.size();
  max_output_age_ns_ = static_cast<int64_t>(daq.max_sample_age_s * 1e9);
  daq_outputs_ = layout_.outputs.size();
  daq_ = std::make_unique<ModbusDaq>(std::move(daq));
  if (valve) {
    valve_ = std::make_unique<CanopenValve>(std::move(*valve));
    for (const auto& c : valve_->input_channels()) layout_.inputs.push_back(c);
    valve_output_ = layout_.outputs.size();
    layout_.outputs.push_back({valve_->config().setpoint_output, "1"});
  }
  // One name, one signal: the loop and the logs address channels by name.
  for (const auto* list : {&layout_.inputs, &layout_.outputs}) {
    for (std::size_t i = 0; i < list->size(); ++i) {
      for (std::size_t j = i + 1; j < list->size(); ++j) {
        if ((*list)[i].name == (*list)[j].name) {
          throw std::invalid_argument("channel '" + (*list)[i].name + "' is given twice (DAQ and valve)");
        }
      }
    }
  }
  if (layout_.inputs.size() > kMaxInputs) throw std::invalid_argument("more input channels than a sample holds");
  if (layout_.outputs.size() > kMaxOutputs) throw std::invalid_argument("more output channels than a command holds");
}

HardwareDriver::~HardwareDriver() {
  try {
    stop();
  } catch (...) {
  }
}

void HardwareDriver::start() {
  daq_->start(first_sample_timeout_s_);
  if (valve_) valve_->start();
  // Rig time starts with the loop, not with the devices' start-up (the
  // valve's SDO configuration takes a good part of a second).
  start_ns_ = ModbusDaq::now_ns();
  lock_step_reads_ = 0;
}

bool HardwareDriver::read(Sample& out) {
  const int64_t now = ModbusDaq::now_ns();
  out.status = 0;
  out.outputs_not_following = 0;
  daq_->read_inputs(out, 0, now);
  if (valve_) {
    valve_->read_actual(out, daq_inputs_, now);
    // Flagged spool actual value: the valve is not (known to be) following
    // the setpoint (it left DEVICE MODE ACTIVE, or is not heard from).
    if ((out.status >> daq_inputs_) & 1U) out.outputs_not_following |= 1U << valve_output_;
  }
  // Lock-step (rig-sim --lock-step): the far side's plant time is the count
  // of reads, one poll period each; otherwise the monotonic clock's.
  const ModbusDaqConfig& daq = daq_->config();
  out.t_ns = daq.lock_step ? lock_step_reads_++ * static_cast<int64_t>(daq.poll_period_s * 1e9 + 0.5) : now - start_ns_;
  // Commands the DAQ could not deliver leave the valve on an old command:
  // as dangerous as stale inputs, so the loop faults.
  return daq_outputs_ == 0 || daq_->output_age_ns(now) <= max_output_age_ns_;
}

void HardwareDriver::write(const Command& command) {
  daq_->write_outputs(command.value.data(), daq_outputs_);
  if (valve_) valve_->write_setpoint(command.value[valve_output_]);
}

void HardwareDriver::make_safe() noexcept {
  daq_->make_safe();
  if (valve_) valve_->make_safe();
}

void HardwareDriver::stop() {
  if (valve_) valve_->stop();
  daq_->stop();
}

std::string HardwareDriver::input_fault_cause(std::size_t input) const {
  if (!valve_ || input < daq_inputs_ || input >= daq_inputs_ + valve_->input_count()) return {};
  return valve_->flag_cause();
}

DriverDiagnostics HardwareDriver::diagnostics() {
  DriverDiagnostics d = daq_->diagnostics();
  if (valve_) {
    DriverDiagnostics v = valve_->diagnostics();
    d.counters.insert(d.counters.end(), v.counters.begin(), v.counters.end());
    d.events.insert(d.events.end(), v.events.begin(), v.events.end());
  }
  return d;
}

}  // namespace rigctl
