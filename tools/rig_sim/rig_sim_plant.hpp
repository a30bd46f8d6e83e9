// `rigctl rig-sim`'s plant on the far side of the wire: it takes the valve command from the
// wire (the DAQ's holding register, with the module's output watchdog, or the
// CANopen valve's spool), steps, and puts its transducers' readings into the
// DAQ's registers. Free-running, rig-sim's main thread calls it once per
// period by the clock; in lock-step the DAQ's server thread calls it once
// per exchange. Either way one thread at a time.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <ostream>
#include <random>
#include <string>
#include <vector>

#include "config/rig_config.hpp"
#include "drivers/sim/sensor_model.hpp"
#include "drivers/sim/sim_canopen_valve.hpp"
#include "drivers/sim/sim_modbus_daq.hpp"
#include "plant/simulated_plant.hpp"
#include "tools/rig_sim/fault_schedule.hpp"
#include "tools/rig_sim/rig_sim.hpp"

namespace rigctl {

class RigSimPlant {
 public:
  RigSimPlant(const RigConfig& config, const ModbusDaqConfig& daq_config, const RigSimOptions& o, SimModbusDaq& daq,
              SimCanopenValve* valve, FaultSchedule& faults, std::ostream& out);
  // Plant time t: the faults due, then the transducers' readings into the registers.
  void measure(double t);
  // The command on the wire at plant time t, for the period from t on.
  void take_command(double t);
  // Twice a second, what the rig does: lets a person (and the end-to-end
  // tests) see that a fault left the valve at null.
  void report(int64_t tick, double t);
  void advance() { plant_->advance(command_, config_.loop.period_s); }

  // Lock-step: one exchange with the controller. The first answers the
  // initial state; each later one steps the plant first with the command
  // the controller sent before its request (the CANopen valve's, once the
  // node has taken the frames already sent).
  void exchange();
  double time(int64_t tick) const { return static_cast<double>(tick) * config_.loop.period_s; }
  double plant_time() const { return plant_time_.load(std::memory_order_acquire); }
  const std::string& valve_name() const { return plant_->commands()[0].name; }
  double null_since() const { return null_since_; }

 private:
  const RigConfig& config_;
  const ModbusDaqConfig& daq_config_;
  const RigSimOptions& o_;
  SimModbusDaq& daq_;
  SimCanopenValve* valve_;
  FaultSchedule& faults_;
  std::ostream& out_;
  std::unique_ptr<SimulatedPlant> plant_;
  std::vector<SensorModel> sensors_;
  std::mt19937_64 rng_;
  std::vector<int> plant_of_input_;
  int valve_daq_output_ = -1;
  std::vector<double> truth_, inputs_, outputs_, command_;
  double null_since_ = -1.0;
  int64_t last_writes_ = 0;
  double last_write_t_ = 0.0;
  bool watchdog_tripped_ = false;
  int64_t exchanges_ = 0;
  std::atomic<double> plant_time_{0.0};
};

}  // namespace rigctl
