#include "tools/rig_sim/rig_sim.hpp"

#include <algorithm>
#include <chrono>
#include <memory>
#include <stdexcept>
#include <thread>

#include "config/config_reader.hpp"
#include "config/rig_config.hpp"
#include "drivers/sim/sim_canopen_valve.hpp"
#include "drivers/sim/sim_modbus_daq.hpp"
#include "rt/loop_clock.hpp"
#include "rt/realtime.hpp"
#include "tools/rig_sim/fault_schedule.hpp"
#include "tools/rig_sim/rig_sim_plant.hpp"

namespace rigctl {

namespace {

ModbusConnection far_side_connection(const RigSimOptions& o, ModbusConnection c) {
  if (!o.modbus_tcp.empty()) {
    const auto colon = o.modbus_tcp.rfind(':');
    if (colon == std::string::npos) throw std::invalid_argument("--modbus expects HOST:PORT, got '" + o.modbus_tcp + "'");
    c.transport = ModbusTransport::kTcp;
    c.host = o.modbus_tcp.substr(0, colon);
    try {
      c.port = std::stoi(o.modbus_tcp.substr(colon + 1));
    } catch (const std::exception&) {
      throw std::invalid_argument("--modbus expects HOST:PORT, got '" + o.modbus_tcp + "'");
    }
  } else {
    c.transport = ModbusTransport::kRtu;
    c.device = o.modbus_rtu;
  }
  return c;
}

// Free-running: one period per period of the monotonic clock.
void run_paced(RigSimPlant& plant, const RigConfig& config, const RigSimOptions& o, const std::atomic<bool>& stop) {
  MonotonicClock clock;
  const auto period_ns = static_cast<int64_t>(config.loop.period_s * 1e9 + 0.5);
  int64_t deadline = clock.now_ns();
  for (int64_t tick = 0;; ++tick) {
    const double t = plant.time(tick);
    if (stop.load() || (o.duration_s && t >= *o.duration_s)) break;
    plant.measure(t);
    plant.take_command(t);
    plant.report(tick, t);
    plant.advance();
    deadline += period_ns;
    clock.sleep_until(deadline);
  }
}

// Lock-step: the DAQ's server thread steps the plant; this one waits for the
// end (a signal, or --duration of plant time).
void run_lock_step(RigSimPlant& plant, const RigSimOptions& o, const std::atomic<bool>& stop) {
  while (!stop.load() && !(o.duration_s && plant.plant_time() >= *o.duration_s)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));  // only how soon a stop is seen
  }
}

}  // namespace

void run_rig_sim(const RigSimOptions& o, const std::atomic<bool>& stop, std::ostream& out) {
  if (o.modbus_tcp.empty() == o.modbus_rtu.empty()) {
    throw std::invalid_argument("rig-sim needs exactly one of --modbus HOST:PORT or --modbus-rtu TTY");
  }
  const RigConfig config = load_rig_config(o.config_path, o.case_name);
  if (!config.modbus) throw ConfigError(config.file + ": modbus: missing (rig-sim exposes the rig's Modbus DAQ)");
  const bool with_valve = !o.can_socket.empty();
  if (with_valve && !config.canopen) throw ConfigError(config.file + ": canopen: missing (needed for --can-socket)");
  if (!with_valve && !o.valve_options.empty()) throw std::invalid_argument("--valve needs the CANopen valve (--can-socket)");

  // The simulated hardware answers like hardware: its threads (created
  // below, inheriting this policy) run at real-time priority when permitted,
  // just under the controller's loop, so a busy machine does not make the
  // far side look faulty.
  RealtimeConfig rt = config.loop.realtime;
  rt.priority = std::max(1, rt.priority - 10);
  rt.cpu = -1;
  RealtimeSession realtime(rt);
  for (const auto& w : realtime.warnings()) out << "rig-sim: " << w << "\n";

  ModbusDaqConfig daq_config = *config.modbus;
  daq_config.connection = far_side_connection(o, daq_config.connection);
  SimModbusDaq daq(daq_config);

  std::unique_ptr<SimCanopenValve> valve;
  if (with_valve) {
    SimCanopenValveConfig vc;
    vc.node_id = config.canopen->node_id;
    vc.setpoint_rpdo = config.canopen->setpoint_rpdo;
    vc.actual_tpdo = config.canopen->actual_tpdo;
    // The plant models the spool lag itself: the node passes the setpoint on.
    vc.spool_time_constant_s = 0.0;
    for (const auto& option : o.valve_options) apply_sim_valve_option(option, vc);
    valve = std::make_unique<SimCanopenValve>(o.can_socket, vc);
  }
  FaultSchedule faults(o.faults, daq, valve.get(), out);
  RigSimPlant plant(config, daq_config, o, daq, valve.get(), faults, out);
  if (o.lock_step) daq.set_exchange_hook([&plant] { plant.exchange(); });
  daq.start();
  out << "rig-sim: modbus listening on " << daq.endpoint() << (o.lock_step ? " (lock-step)" : "") << "\n";
  if (valve) out << "rig-sim: canopen valve on " << o.can_socket << "\n";
  out.flush();

  if (o.lock_step) {
    run_lock_step(plant, o, stop);
  } else {
    run_paced(plant, config, o, stop);
  }
  daq.stop();  // first: in lock-step its thread steps the plant, which reads the valve
  if (valve) valve.reset();
  if (plant.null_since() >= 0.0) out << "rig-sim: valve " << plant.valve_name() << " = 0 since t = " << plant.null_since() << " s\n";
  out << "rig-sim: stopped\n";
}

}  // namespace rigctl
