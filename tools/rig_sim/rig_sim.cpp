#include "tools/rig_sim/rig_sim.hpp"

#include <chrono>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <stdexcept>
#include <thread>

#include "config/config_reader.hpp"
#include "config/rig_config.hpp"
#include "drivers/sim/sensor_model.hpp"
#include "drivers/sim/sim_canopen_valve.hpp"
#include "drivers/sim/sim_modbus_daq.hpp"
#include "rt/loop_clock.hpp"
#include "rt/realtime.hpp"
#include "tools/run/rig_assembly.hpp"

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

std::size_t daq_input_index(const ModbusDaqConfig& daq, const std::string& channel, const std::string& fault) {
  for (std::size_t i = 0; i < daq.inputs.size(); ++i) {
    if (daq.inputs[i].name == channel) return i;
  }
  throw std::invalid_argument("fault '" + fault + "': '" + channel + "' is not a DAQ input");
}

class FaultSchedule {
 public:
  FaultSchedule(std::vector<FaultSpec> faults, SimModbusDaq& daq, SimCanopenValve* valve, std::ostream& out)
      : faults_(std::move(faults)), started_(faults_.size(), false), ended_(faults_.size(), false), daq_(daq),
        valve_(valve), out_(out) {
    for (const auto& f : faults_) {
      if (!fault_on_wire(f.kind)) {
        throw std::invalid_argument("fault '" + f.text + "' is injected in the simulated driver: `rigctl run --fault` with driver: sim");
      }
      if ((f.kind == FaultKind::kHeartbeat || f.kind == FaultKind::kEmcy || f.kind == FaultKind::kHold) &&
          valve_ == nullptr) {
        throw std::invalid_argument("fault '" + f.text + "' needs the CANopen valve (--can-socket)");
      }
      if (f.kind == FaultKind::kException || f.kind == FaultKind::kStuck || f.kind == FaultKind::kRail) {
        daq_input_index(daq_.client_config(), f.channel, f.text);  // fail before running
      }
    }
  }

  // Not on a real-time path of its own: rig-sim's plant thread calls it once
  // per period; fault changes are rare.
  void apply(double t) {
    for (std::size_t i = 0; i < faults_.size(); ++i) {
      const auto& f = faults_[i];
      if (!started_[i] && t >= f.at_s) {
        started_[i] = true;
        begin(f);
        out_ << "rig-sim: t = " << t << " s: fault " << f.text << "\n";
        out_.flush();
      }
      if (started_[i] && !ended_[i] && f.duration_s > 0.0 && t >= f.at_s + f.duration_s) {
        ended_[i] = true;
        end(f);
        out_ << "rig-sim: t = " << t << " s: fault " << f.text << " cleared\n";
        out_.flush();
      }
    }
  }

 private:
  void begin(const FaultSpec& f) {
    const auto cfg = daq_.client_config();
    switch (f.kind) {
      case FaultKind::kSilence: daq_.set_silent(true); break;
      case FaultKind::kDrop: daq_.drop_connections(); break;
      case FaultKind::kLate: daq_.set_reply_delay(f.delay_s); break;
      case FaultKind::kException: {
        const auto& p = cfg.inputs[daq_input_index(cfg, f.channel, f.text)].point;
        daq_.add_exception({p.unit_id, p.type, p.address, p.address + register_count(p.format) - 1, f.code});
        break;
      }
      case FaultKind::kStuck: daq_.set_stuck(daq_input_index(cfg, f.channel, f.text), true); break;
      case FaultKind::kRail: {
        // The top of the register's range: what an open-circuit transducer
        // drives the ADC to.
        const auto& p = cfg.inputs[daq_input_index(cfg, f.channel, f.text)].point;
        const double rail = p.format == DataFormat::kInt16 ? 32767.0
                            : p.format == DataFormat::kUint16 ? 65535.0
                            : p.format == DataFormat::kInt32 ? 2147483647.0
                            : p.format == DataFormat::kUint32 ? 4294967295.0
                                                               : 3.0e38;
        daq_.force_raw(daq_input_index(cfg, f.channel, f.text), rail);
        break;
      }
      case FaultKind::kHeartbeat: valve_->miss_heartbeats(f.duration_s > 0.0 ? f.duration_s : 1e9); break;
      case FaultKind::kEmcy:
        valve_->send_emcy(static_cast<uint16_t>(f.code), static_cast<uint8_t>(f.error_register));
        break;
      case FaultKind::kHold: valve_->drop_to_hold(f.duration_s > 0.0 ? f.duration_s : 1e9); break;
      default: break;  // not on the wire: refused by the constructor
    }
  }

  void end(const FaultSpec& f) {
    switch (f.kind) {
      case FaultKind::kSilence: daq_.set_silent(false); break;
      case FaultKind::kLate: daq_.set_reply_delay(0.0); break;
      default: break;  // one-off or until the end
    }
  }

  std::vector<FaultSpec> faults_;
  std::vector<bool> started_, ended_;
  SimModbusDaq& daq_;
  SimCanopenValve* valve_;
  std::ostream& out_;
};

// The plant on the far side of the wire: it takes the valve command from the
// wire (the DAQ's holding register, with the module's output watchdog, or the
// CANopen valve's spool), steps, and puts its transducers' readings into the
// DAQ's registers. Free-running, rig-sim's main thread calls it once per
// period by the clock; in lock-step the DAQ's server thread calls it once
// per exchange. Either way one thread at a time.
class RigSimPlant {
 public:
  RigSimPlant(const RigConfig& config, const ModbusDaqConfig& daq_config, const RigSimOptions& o, SimModbusDaq& daq,
              SimCanopenValve* valve, FaultSchedule& faults, std::ostream& out)
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

  // Plant time t: the faults due, then the transducers' readings into the registers.
  void measure(double t) {
    faults_.apply(t);
    plant_->measure(truth_);
    for (std::size_t i = 0; i < inputs_.size(); ++i) {
      inputs_[i] = sensors_[i].measure(truth_[static_cast<std::size_t>(plant_of_input_[i])], rng_);
    }
    daq_.set_inputs(inputs_.data(), inputs_.size());
  }

  // The command on the wire at plant time t, for the period from t on.
  void take_command(double t) {
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

  // Twice a second, what the rig does: lets a person (and the end-to-end
  // tests) see that a fault left the valve at null.
  void report(int64_t tick, double t) {
    if (tick % std::max<int64_t>(1, std::llround(0.5 / config_.loop.period_s)) != 0) return;
    out_ << "rig-sim: t = " << t << " s, valve " << plant_->commands()[0].name << " = " << command_[0];
    for (std::size_t i = 0; i < inputs_.size() && i < 3; ++i) out_ << ", " << daq_config_.inputs[i].name << " = " << inputs_[i];
    out_ << "\n";
    out_.flush();
  }

  void advance() { plant_->advance(command_, config_.loop.period_s); }

  // Lock-step: one exchange with the controller. The first answers the
  // initial state; each later one steps the plant first with the command
  // the controller sent before its request (the CANopen valve's, once the
  // node has taken the frames already sent).
  void exchange() {
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
