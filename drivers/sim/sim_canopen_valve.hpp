// A simulated CiA 408 servovalve node: the far side of CanopenValve, for the
// simulated rig (rig-sim) and the tests. It serves the object dictionary
// subset the client configures, runs the NMT state machine (boot-up,
// pre-operational, operational, stopped, resets), produces its heartbeat,
// consumes the master's heartbeat and goes to its fail-safe when it is lost,
// moves the spool as a first-order lag toward the setpoint and sends the
// spool actual value by TPDO. Faults can be injected from any thread.
//
// Behaviour, in the terms of CiA 301/408:
//  * The spool follows the RPDO setpoint only while NMT operational, device
//    mode 0x6042 = 1 (setpoint via bus; the default is 0, so the client's
//    start-up SDO writes matter), control word MHD = 111 (ACTIVE) and no
//    device fault. Otherwise its target is null (0).
//  * TPDO: the spool actual value (status word, spool actual [, pressure]) is
//    sent every tpdo_period_s while operational (transmission type 255 with
//    an event timer; SYNC is not implemented: the loop's period and the
//    valve's cycle stay independent and the client bounds the age of what it
//    uses). Writing the event timer 0x1800+n-1 sub 5 (ms, > 0) changes the
//    period; the other PDO communication objects are stored only.
//  * Heartbeat: produced every 0x1017 ms (0: off). Master heartbeat consumer
//    0x1016:1 (node << 16 | ms); monitoring starts with the first master
//    heartbeat. When it times out: spool target null, device state
//    FAULT_HOLD (status word 0x0003: ready bit clear), error register 0x11,
//    EMCY 0x8130 and NMT pre-operational (the CiA 301 default error
//    behaviour). The fault clears on a rising edge of control word bit 3
//    (fault reset), an NMT reset or a new connection.
//  * NMT reset communication restores 0x1000-0x1FFF, reset node the whole
//    dictionary; both send the boot-up message and enter pre-operational.
//  * Listening on a socket path, each accepted connection is a power-on
//    (dictionary defaults, boot-up); after a disconnect the next connection
//    is served.
#pragma once

#include <atomic>
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

namespace rigctl {

struct SimCanopenValveConfig {
  uint8_t node_id = 1;
  double spool_time_constant_s = 0.004;  // first-order lag of the spool
  double tpdo_period_s = 0.001;          // spool actual value sent this often while operational (until 0x1800:5 is written)
  int setpoint_rpdo = 1;
  int actual_tpdo = 1;
  bool with_pressure = false;            // TPDO carries the pressure actual value 0x6381:1
  double pressure_scale_pa = 1.0;        // Pa per count
  uint16_t heartbeat_period_ms = 0;      // 0x1017 at power-on (0: off until configured)
  uint32_t vendor_id = 0x0000'0000;      // 0x1018 identity (simulated)
  uint32_t product_code = 0x0000'0408;
  uint32_t revision = 0x0001'0000;
  uint32_t serial = 1;
};

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
  // Pressure reported in the TPDO (when mapped), Pa.
  void set_pressure(double pa) noexcept { pressure_.store(pa, std::memory_order_release); }

  canopen::NmtState nmt_state() const noexcept {
    return static_cast<canopen::NmtState>(nmt_.load(std::memory_order_acquire));
  }
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

 private:
  struct Outgoing {
    int64_t due_ns = 0;
    canopen::CanFrame frame;
    std::vector<uint8_t> raw;  // non-empty: send these bytes instead of `frame`
  };

  void run();
  void serve(int64_t now);
  void power_on(int64_t now);
  void reset_communication(int64_t now, bool whole_dictionary);
  void handle(const canopen::CanFrame& f, int64_t now);
  void handle_nmt(const canopen::CanFrame& f, int64_t now);
  void handle_rpdo(const canopen::CanFrame& f);
  void handle_sdo(const canopen::CanFrame& f, int64_t now);
  void after_write(uint16_t index, uint8_t subindex, int64_t now);
  void apply_control_word(uint16_t cw);
  void step(int64_t now);
  void enter_fail_safe(int64_t now);
  void queue(const canopen::CanFrame& f, int64_t now);
  void flush(int64_t now);
  int wait_ms(int64_t now) const;
  void set_nmt(canopen::NmtState s) { nmt_state_ = s; nmt_.store(static_cast<uint8_t>(s), std::memory_order_release); }
  canopen::OdEntry& od(uint16_t index, uint8_t subindex);
  uint16_t status_word() const;

  const SimCanopenValveConfig config_;
  canopen::PdoMapping rpdo_map_;
  canopen::PdoMapping tpdo_map_;
  uint32_t setpoint_cob_ = 0;
  uint32_t actual_cob_ = 0;

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
  canopen::NmtState nmt_state_ = canopen::NmtState::kBootUp;
  canopen::HeartbeatProducer producer_{0, 0};
  canopen::HeartbeatConsumer consumer_{0, 0};
  std::deque<Outgoing> out_;
  double setpoint_ = 0.0;        // fraction, from RPDO/SDO
  double spool_state_ = 0.0;
  uint16_t control_word_ = 0x0001;
  int64_t last_step_ns_ = 0;
  int64_t next_tpdo_ns_ = 0;
  int64_t tpdo_period_ns_ = 0;
  int64_t miss_heartbeats_until_ns_ = 0;
  int64_t delay_ns_ = 0;
  int64_t fail_safe_ns_ = 0;
  bool silent_ = false;
  bool drop_requested_ = false;
  Stats stats_;

  std::atomic<double> spool_{0.0};
  std::atomic<double> pressure_{0.0};
  std::atomic<uint8_t> nmt_{0};
  std::atomic<bool> connected_{false};
  std::atomic<bool> fault_{false};
};

}  // namespace rigctl
