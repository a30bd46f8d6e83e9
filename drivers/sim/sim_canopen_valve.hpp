// A simulated CiA 408 servovalve node: the far side of CanopenValve, for the
// simulated rig (rig-sim) and the tests. It serves an object dictionary,
// runs the NMT state machine (initialisation, boot-up, pre-operational,
// operational, stopped, resets) and the CiA 408 device state machine,
// produces its heartbeat, consumes the master's and goes to its fail-safe
// when it is lost, takes its PDO mapping from the dictionary, moves the
// spool as a first-order lag toward the setpoint and sends the spool actual
// value by TPDO. Faults can be injected from any thread; the behaviours of
// real valves a client must cope with are options
// (sim_canopen_valve_config.hpp).
//
// Behaviour, in the terms of CiA 301/408:
//  * Initialisation: after power-on (a new connection) and each NMT reset
//    the node is silent for boot_delay_s and ignores what it receives
//    (counted), then sends its boot-up message and enters pre-operational.
//  * Device state machine (sim_valve_device_state.hpp): from INIT the
//    control word (by SDO 0x6040 or in the RPDO) walks it to DEVICE MODE
//    ACTIVE, or as far as the stall option lets it. The spool follows the
//    RPDO setpoint only while NMT operational, device mode 0x6042 = 1
//    (setpoint via bus; the default is 0, so the client's start-up writes
//    matter) and ACTIVE; in HOLD and FAULT_HOLD it goes to the hold setpoint
//    0x6314:1 (0), otherwise to its fail-safe null.
//  * PDOs: the mapping is the dictionary's (0x1600/0x1A00 + n - 1; at
//    power-on the profile's or a minimal one), changed by the CiA 301 rules
//    (sim_valve_dictionary.hpp) and used from when the PDO is valid. The
//    TPDO is sent every event timer 0x1800+n-1:5 ms while operational
//    (SYNC is not implemented: the loop's period and the valve's cycle stay
//    independent and the client bounds the age of what it uses). An RPDO
//    whose length differs from the mapping raises EMCY 0x8210 (too short) or
//    0x8220 (too long). The RPDO event timer 0x1400+n-1:5 (ms, > 0) is a
//    deadline: with none received in time after the first, EMCY 0x8250, the
//    DSM faults and the spool goes to null.
//  * Heartbeat: produced every 0x1017 ms (0: off). Master heartbeat consumer
//    0x1016:1 (node << 16 | ms); monitoring starts with the first master
//    heartbeat. When it times out: the DSM faults (FAULT_HOLD, ready bit
//    clear), error register 0x11, EMCY 0x8130 and NMT pre-operational (the
//    CiA 301 default error behaviour). A fault clears on a rising edge of
//    control word bit 3 (fault reset), an NMT reset or a new connection.
//  * NMT reset communication restores 0x1000-0x1FFF, reset node the whole
//    dictionary and the device state machine.
//  * Listening on a socket path, each accepted connection is a power-on;
//    after a disconnect the next connection is served.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "drivers/canopen/can_transport.hpp"
#include "drivers/canopen/protocol/nmt.hpp"
#include "drivers/canopen/protocol/pdo.hpp"
#include "drivers/canopen/protocol/sdo.hpp"
#include "drivers/sim/sim_canopen_valve_config.hpp"
#include "drivers/sim/sim_valve_device_state.hpp"
#include "drivers/sim/sim_valve_dictionary.hpp"

namespace rigctl {

class SimCanopenValve {
 public:
  // Listens on `socket_path`; serves one connection at a time. Throws
  // std::runtime_error when the socket cannot be made.
  SimCanopenValve(const std::string& socket_path, SimCanopenValveConfig config);
  // Serves one already connected transport (one end of a socketpair).
  SimCanopenValve(CanTransport transport, SimCanopenValveConfig config);
  ~SimCanopenValve();
  SimCanopenValve(const SimCanopenValve&) = delete;
  SimCanopenValve& operator=(const SimCanopenValve&) = delete;

  // The valve opening the plant uses: spool position, fraction of rated, -1..1.
  double spool() const noexcept { return spool_.load(std::memory_order_acquire); }
  // Returns once the node has taken every frame that was in its socket when
  // called (two whole passes of its thread later): `rig-sim --lock-step`
  // steps the plant with the setpoint the controller sent before its DAQ
  // request. Returns at once when the node is stopping.
  void take_pending_frames();
  // Pressure reported in the TPDO (when mapped), Pa.
  void set_pressure(double pa) noexcept { pressure_.store(pa, std::memory_order_release); }

  canopen::NmtState nmt_state() const noexcept {
    return static_cast<canopen::NmtState>(nmt_.load(std::memory_order_acquire));
  }
  canopen::cia408::ValveState device_state() const;
  bool connected() const noexcept { return connected_.load(std::memory_order_acquire); }
  bool fail_safe() const noexcept { return fault_.load(std::memory_order_acquire); }
  // Value of an object dictionary entry (nullopt if the dictionary lacks it).
  std::optional<uint32_t> od_value(uint16_t index, uint8_t subindex) const;

  struct Stats {
    uint64_t connections = 0;
    uint64_t rpdos = 0;           // setpoints taken
    uint64_t sdo_writes = 0;      // successful SDO downloads
    uint64_t nmt_commands = 0;
    uint64_t master_heartbeat_losses = 0;
    uint64_t malformed = 0;       // frames received and dropped
    uint64_t boot_ups = 0;        // boot-up messages sent
    uint64_t sdo_while_booting = 0;  // SDO requests received while initialising (ignored: a real node is deaf then)
    uint64_t rpdo_timeouts = 0;
    uint64_t pdo_length_errors = 0;
  };
  Stats stats() const;
  // Time (CLOCK_MONOTONIC ns) of the last master heartbeat and of the last
  // fail-safe; 0 when none.
  int64_t last_master_heartbeat_ns() const;
  int64_t fail_safe_ns() const;

  // ---- fault injection (thread-safe) ----
  void drop_connection();                 // close the current connection
  void set_silent(bool silent);           // send nothing at all (heartbeat, TPDO, SDO answers); keep listening
  void set_response_delay(double s);      // every frame leaves `s` later than it would (in order)
  void miss_heartbeats(double duration_s);  // suppress our heartbeat for a while
  void send_emcy(uint16_t code, uint8_t error_register);
  void send_raw(const canopen::CanFrame& frame);       // any frame, e.g. malformed ones
  void send_raw_record(std::vector<uint8_t> bytes);    // a record that is not 16 bytes
  void reset_node();                      // the valve resets itself (boot-up, pre-operational)
  void drop_to_hold(double duration_s);   // an internal event holds an ACTIVE valve in HOLD for a while
  void lose_sdo_answers(int count);       // the next `count` SDO answers are lost on the way
  void fault_device(uint16_t emcy_code);  // a device fault: FAULT_DISABLED/FAULT_HOLD, EMCY, until a fault reset

 private:
  struct Outgoing {
    int64_t due_ns = 0;
    canopen::CanFrame frame;
    std::vector<uint8_t> raw;  // non-empty: send these bytes instead of `frame`
  };

  void run();
  void serve_frames();
  void power_on(int64_t now);
  void reset_communication(int64_t now, bool whole_dictionary);
  void finish_boot(int64_t now);
  void handle(const canopen::CanFrame& f, int64_t now);
  void handle_nmt(const canopen::CanFrame& f, int64_t now);
  void handle_rpdo(const canopen::CanFrame& f, int64_t now);
  void handle_sdo(const canopen::CanFrame& f, int64_t now);
  void after_write(uint16_t index, uint8_t subindex, int64_t now);
  void apply_control_word(uint16_t cw, int64_t now);
  void refresh_pdos();
  void step(int64_t now);
  void watch_deadlines(int64_t now);
  void send_tpdo(int64_t now);
  void enter_fail_safe(int64_t now, uint16_t emcy_code);
  void queue(const canopen::CanFrame& f, int64_t now);
  void flush(int64_t now);
  int wait_ms(int64_t now) const;
  void set_nmt(canopen::NmtState s) { nmt_state_ = s; nmt_.store(static_cast<uint8_t>(s), std::memory_order_release); }
  bool booting(int64_t now) const { return boot_until_ns_ != 0 && now < boot_until_ns_; }
  canopen::OdEntry& od(uint16_t index, uint8_t subindex);
  double spool_scale() const { return 1.0 / config_.spool_reference; }

  const SimCanopenValveConfig config_;

  std::unique_ptr<SeqpacketListener> listener_;
  std::thread thread_;
  std::atomic<bool> stop_{false};

  // Everything below is guarded by mutex_ (the node thread holds it while it
  // handles frames and steps; the injectors and accessors take it briefly).
  mutable std::mutex mutex_;
  CanTransport transport_;
  std::vector<canopen::OdEntry> od_;
  std::vector<canopen::OdEntry> od_defaults_;
  std::unique_ptr<canopen::SdoServer> sdo_;
  SimPdo rpdo_;
  SimPdo tpdo_;
  SimValveDeviceState dsm_;
  canopen::NmtState nmt_state_ = canopen::NmtState::kBootUp;
  canopen::HeartbeatProducer producer_{0, 0};
  canopen::HeartbeatConsumer consumer_{0, 0};
  std::deque<Outgoing> out_;
  double setpoint_ = 0.0;        // fraction, from RPDO/SDO
  double spool_state_ = 0.0;
  int64_t boot_until_ns_ = 0;    // initialising until then (0: not booting)
  int64_t last_step_ns_ = 0;
  int64_t next_tpdo_ns_ = 0;
  int64_t tpdo_period_ns_ = 0;
  int64_t rpdo_deadline_ns_ = 0;  // 0: not monitored (no RPDO yet, or no event timer)
  int64_t miss_heartbeats_until_ns_ = 0;
  int64_t delay_ns_ = 0;
  int64_t fail_safe_ns_ = 0;
  bool silent_ = false;
  bool drop_requested_ = false;
  int sdo_answers_to_lose_ = 0;
  Stats stats_;
  uint64_t passes_ = 0;                // the node thread's passes (receive, handle, step)
  std::condition_variable pass_done_;  // with mutex_, after each pass

  std::atomic<double> spool_{0.0};
  std::atomic<double> pressure_{0.0};
  std::atomic<uint8_t> nmt_{0};
  std::atomic<bool> connected_{false};
  std::atomic<bool> fault_{false};
};

}  // namespace rigctl
