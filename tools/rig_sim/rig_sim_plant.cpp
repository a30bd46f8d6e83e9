#include "tools/rig_sim/rig_sim_plant.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "config/config_reader.hpp"
#include "tools/run/rig_assembly.hpp"

namespace rigctl {

namespace {

// The transducers of the physical rig: noise and offset on the plant's true
// values. No ADC quantisation here: the DAQ's registers quantise.
std::vector<SensorModel> transducers(const RigConfig& c, const ModbusDaqConfig& daq) {
  std::vector<SensorModel> out;
  for (const auto& ch : daq.inputs) {
    SensorSpec spec;
    if (const auto it = c.sensors.find(ch.name); it != c.sensors.end()) {
      spec.noise_sd = it->second.noise_sd;
      spec.offset = it->second.offset;
    }
    out.emplace_back(spec);
  }
  return out;
}

int signal_index(const SimulatedPlant& plant, const std::string& name, const std::string& what) {
  const auto& s = plant.signals();
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i].name == name) return static_cast<int>(i);
  }
  throw std::invalid_argument(what + " '" + name + "' is not a signal of the simulated plant");
}

}  // namespace

RigSimPlant::RigSimPlant(const RigConfig& config, const ModbusDaqConfig& daq_config, const RigSimOptions& o,
                         SimModbusDaq& daq, SimCanopenValve* valve, FaultSchedule& faults, std::ostream& out)
    : config_(config), daq_config_(daq_config), o_(o), daq_(daq), valve_(valve), faults_(faults), out_(out),
      plant_(make_plant(config)), sensors_(transducers(config, daq_config)), rng_(config.seed) {
  plant_->reset();
  for (const auto& ch : daq_config.inputs) plant_of_input_.push_back(signal_index(*plant_, ch.name, "DAQ input"));
  for (std::size_t i = 0; i < daq_config.outputs.size(); ++i) {
    if (daq_config.outputs[i].name == plant_->commands().at(0).name) valve_daq_output_ = static_cast<int>(i);
  }
  if (valve_ == nullptr && valve_daq_output_ < 0) {
    throw ConfigError(config.file + ": modbus.outputs: no output named '" + plant_->commands().at(0).name +
                      "' drives the valve (or give --can-socket for a CANopen valve)");
  }
  truth_.resize(plant_->signals().size());
  inputs_.resize(daq_config.inputs.size());
  outputs_.resize(daq_config.outputs.size());
  command_.assign(plant_->commands().size(), 0.0);
}

void RigSimPlant::measure(double t) {
  faults_.apply(t);
  plant_->measure(truth_);
  for (std::size_t i = 0; i < inputs_.size(); ++i) {
    inputs_[i] = sensors_[i].measure(truth_[static_cast<std::size_t>(plant_of_input_[i])], rng_);
  }
  daq_.set_inputs(inputs_.data(), inputs_.size());
}

void RigSimPlant::take_command(double t) {
  if (valve_ != nullptr) {
    command_[0] = valve_->spool();
  } else {
    daq_.outputs(outputs_.data());
    if (const int64_t w = daq_.writes(); w != last_writes_) {
      last_writes_ = w;
      last_write_t_ = t;
      watchdog_tripped_ = false;
    } else if (o_.output_watchdog_s > 0.0 && t - last_write_t_ > o_.output_watchdog_s) {
      if (!watchdog_tripped_) {
        out_ << "rig-sim: t = " << t << " s: output watchdog: no write for " << o_.output_watchdog_s
             << " s, outputs at their safe values\n";
        watchdog_tripped_ = true;
      }
      for (std::size_t i = 0; i < outputs_.size(); ++i) outputs_[i] = daq_config_.outputs[i].safe;
    }
    command_[0] = outputs_[static_cast<std::size_t>(valve_daq_output_)];
  }
  if (!std::isfinite(command_[0])) command_[0] = 0.0;
  // Where the final stretch of null commands began: after a fault, the time
  // the valve reached its safe value as the rig saw it (printed at the end).
  if (command_[0] != 0.0) {
    null_since_ = -1.0;
  } else if (null_since_ < 0.0) {
    null_since_ = t;
  }
}

void RigSimPlant::report(int64_t tick, double t) {
  if (tick % std::max<int64_t>(1, std::llround(0.5 / config_.loop.period_s)) != 0) return;
  out_ << "rig-sim: t = " << t << " s, valve " << plant_->commands()[0].name << " = " << command_[0];
  for (std::size_t i = 0; i < inputs_.size() && i < 3; ++i) out_ << ", " << daq_config_.inputs[i].name << " = " << inputs_[i];
  out_ << "\n";
  out_.flush();
}

void RigSimPlant::exchange() {
  if (exchanges_ > 0) {
    if (valve_ != nullptr) valve_->take_pending_frames();
    take_command(time(exchanges_ - 1));
    advance();
  }
  const double t = time(exchanges_);
  measure(t);
  report(exchanges_, t);
  plant_time_.store(t, std::memory_order_release);
  ++exchanges_;
}

}  // namespace rigctl
