#include "drivers/sim/sim_driver.hpp"

#include <algorithm>
#include <stdexcept>

namespace rigctl {

SimDriver::SimDriver(std::unique_ptr<SimulatedPlant> plant, std::vector<SensorSpec> sensors,
                     std::vector<SensorSpec> dacs, double period_s, uint64_t seed, std::vector<double> safe_command)
    : plant_(std::move(plant)), period_s_(period_s), period_ns_(static_cast<int64_t>(period_s * 1e9 + 0.5)), seed_(seed), safe_command_(std::move(safe_command)) {
  layout_.inputs = plant_->signals();
  layout_.outputs = plant_->commands();
  if (layout_.inputs.size() > kMaxInputs) throw std::invalid_argument("plant has more signals than a Sample holds");
  if (layout_.outputs.size() > kMaxOutputs) throw std::invalid_argument("plant has more commands than a Command holds");
  if (sensors.size() != layout_.inputs.size()) throw std::invalid_argument("one sensor spec per plant signal is needed");
  if (safe_command_.size() != layout_.outputs.size()) throw std::invalid_argument("safe command size differs from outputs");
  if (dacs.size() != layout_.outputs.size()) throw std::invalid_argument("one DAC spec per plant command is needed");
  for (const auto& s : sensors) {
    if (!(s.delay_s >= 0.0)) throw std::invalid_argument("sensor delay must be >= 0 s");
    sensor_specs_.push_back(s);
    sensors_.emplace_back(s);
    if (!(s.filter_hz >= 0.0)) throw std::invalid_argument("sensor filter cut-off must be >= 0 Hz");
    delays_.emplace_back(s.delay_s, period_s);
    filters_.emplace_back(s.filter_hz, period_s);
  }
  for (auto d : dacs) {
    d.noise_sd = 0.0;  // a DAC quantises and clips; its noise belongs to the plant
    dacs_.emplace_back(d);
  }
  command_ = safe_command_;
  truth_.assign(layout_.inputs.size(), 0.0);
}

void SimDriver::start() {
  plant_->reset();
  rng_.seed(seed_);
  command_ = safe_command_;
  for (std::size_t i = 0; i < delays_.size(); ++i) delays_[i] = DelayLine(sensors_[i].delay_s(), period_s_);
  for (std::size_t i = 0; i < filters_.size(); ++i) filters_[i] = ConditioningFilter(sensors_[i].filter_hz(), period_s_);
  tick_ = 0;
  started_ = false;
  faults_.reset();
  safe_since_ns_.store(0, std::memory_order_relaxed);
}

void SimDriver::set_faults(const std::vector<FaultSpec>& faults) {
  faults_ = SimFaults(faults, layout_, sensor_specs_, *plant_, period_s_, seed_);
}

bool SimDriver::read(Sample& out) {
  // The command written on the previous tick acts over the period that just
  // ended (zero-order hold, as a DAC does).
  if (started_) {
    plant_->advance(command_, period_s_);
    ++tick_;
  }
  started_ = true;
  if (!faults_.empty()) {
    faults_.apply_to_plant(tick_);
    if (const int stall = faults_.stall_periods(tick_); stall > 0) {
      // The read is late: the loop's clock moves on by the stall and so does
      // the plant, with the held command, as a rig does while its controller
      // waits. The sample is the one at the end of the stall.
      if (stall_clock_ != nullptr) stall_clock_->sleep_until(stall_clock_->now_ns() + stall * period_ns_);
      for (int k = 0; k < stall; ++k) {
        plant_->advance(command_, period_s_);
        ++tick_;
      }
      faults_.apply_to_plant(tick_);
    }
  }
  plant_->measure(truth_);
  out.t_ns = tick_ * period_ns_;
  out.status = 0;
  for (std::size_t i = 0; i < truth_.size(); ++i) {
    const double conditioned = filters_[i].active() ? filters_[i].push(truth_[i]) : truth_[i];
    const double seen = delays_[i].active() ? delays_[i].push(conditioned) : conditioned;
    out.value[i] = sensors_[i].measure(seen, rng_);
  }
  if (!faults_.empty()) faults_.apply_to_sample(tick_, out);
  return true;
}

void SimDriver::write(const Command& command) {
  for (std::size_t i = 0; i < command_.size(); ++i) command_[i] = dacs_[i].measure(command.value[i], rng_);
  safe_since_ns_.store(-1, std::memory_order_relaxed);
}

void SimDriver::make_safe() noexcept {
  std::copy(safe_command_.begin(), safe_command_.end(), command_.begin());
  if (safe_since_ns_.load(std::memory_order_relaxed) < 0) safe_since_ns_.store(tick_ * period_ns_, std::memory_order_relaxed);
}

DriverDiagnostics SimDriver::diagnostics() {
  DriverDiagnostics d;
  if (faults_.empty()) return d;  // nothing to say: no status messages in an ordinary run
  d.counters.emplace_back("sim_faults_injected", faults_.injected_count());
  d.counters.emplace_back("sim_valve_safe_since_ns", safe_since_ns_.load(std::memory_order_relaxed));
  d.events = faults_.take_new_reports();
  return d;
}

}  // namespace rigctl
