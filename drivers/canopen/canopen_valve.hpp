// Client of a CiA 408 servovalve on CANopen: writes the spool setpoint and
// reads back the spool actual value (and a pressure, if mapped) by PDO,
// configures the valve by SDO, starts it by NMT and walks its device state
// machine to DEVICE MODE ACTIVE, and watches it by heartbeat, EMCY and
// status word. Not a Driver itself: the rig's hardware driver composes it
// with its DAQ and calls the real-time API below from read()/write().
//
// Start-up (start(), canopen_valve_startup.cpp), within startup_timeout_s:
//  1. NMT reset communication (reset_on_start): frames queued before it are
//     discarded, so an earlier boot-up cannot pass for its answer, and the
//     boot-up that follows it is awaited (boot_timeout_s);
//  2. identity 0x1000/0x1018: a device type whose profile number is not 408
//     is refused;
//  3. heartbeats 0x1017, 0x1016:1 (configure_heartbeats);
//  4. the setpoint RPDO and the actual-value TPDO by the CiA 301 sequence
//     (configure_pdos; canopen/protocol/pdo_setup.hpp), then read back and
//     checked either way: a refusal names the object and the abort code;
//  5. the spool scale from the reference value 0x6311:1 (or configured, and
//     checked against it);
//  6. the config's start-up SDO writes, NMT start, a heartbeat reporting
//     operational and a first actual value;
//  7. the device state machine walked by the RPDO's control word (null
//     setpoint) one state at a time to DEVICE MODE ACTIVE, each step within
//     device_state_timeout_s; a valve that does not get there is refused.
// Every SDO request that times out is sent once more before start-up fails.
//
// Threads:
//  * start()/stop()/diagnostics(): the caller's (non-real-time) thread.
//    start() runs the start-up sequence on the calling thread, then starts
//    the I/O thread; stop() ends it. During start-up the calling thread
//    produces our heartbeat, which the valve watches from 0x1016:1 on, so it
//    runs at io_priority (SCHED_FIFO) meanwhile, as the I/O thread does after.
//  * I/O thread (io_priority): receives every frame (TPDO actual value,
//    heartbeat, EMCY, SDO responses), sends our heartbeat and, while the
//    loop holds the valve safe (before its first setpoint and after
//    make_safe()), repeats the null setpoint so the valve's RPDO deadline
//    (setpoint_timeout_s) does not expire; keeps counters and events. It
//    owns the protocol state machines.
//  * The real-time loop: write_setpoint(), make_safe(), read_actual(),
//    healthy(). No allocation, no lock, no blocking: the setpoint RPDO is
//    encoded and sent directly with a non-blocking send (one syscall, ~µs)
//    instead of handing it to the I/O thread, whose wake-up would add a
//    cross-CPU hop (~50 µs here). The actual value comes from the I/O thread
//    through a sequence lock.
//
// Times passed to the real-time API are CLOCK_MONOTONIC nanoseconds (what
// rt/loop_clock.hpp's MonotonicClock gives; clock_ns() here).
//
// Fail-safe: read_actual() flags its inputs invalid (Sample::status bits) when
// the spool actual value is older than actual_max_age_s or was never
// received, when the valve's last heartbeat is older than heartbeat_timeout_s
// (checked on the loop's own clock, so a stalled I/O thread cannot hide it),
// when the valve's heartbeat reports any NMT state but operational, when its
// status word reports any device state but DEVICE MODE ACTIVE (in HOLD,
// DISABLED, INIT and the fault states the valve ignores the bus setpoint),
// when the valve reset itself, when an EMCY with a non-zero error register is
// active, or when the connection is lost. The loop's limit check then faults
// on that tick and make_safe() sends the null setpoint at once: for a lost
// heartbeat at most floor(heartbeat_timeout_s / period) + 1 loop periods
// after the last heartbeat arrived (21 periods for 50 ms at 2.5 ms). The
// valve itself goes to its safe state when our heartbeat stops for its
// consumer time (valve_consumer_time_s, 0x1016:1) or our setpoints for
// setpoint_timeout_s (0x1400+n-1:5). Heartbeat loss, a valve reset, a
// departure from DEVICE MODE ACTIVE and a lost connection stay latched until
// stop()/start(): a flaky link must not silently resume control. The first
// reason the inputs were flagged is kept for the session: flag_cause().
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "drivers/canopen/can_transport.hpp"
#include "drivers/canopen/protocol/cia408.hpp"
#include "drivers/canopen/protocol/emcy.hpp"
#include "drivers/canopen/protocol/frame_stats.hpp"
#include "drivers/canopen/protocol/nmt.hpp"
#include "drivers/canopen/protocol/pdo.hpp"
#include "drivers/canopen/protocol/pdo_setup.hpp"
#include "drivers/canopen/protocol/sdo.hpp"
#include "drivers/canopen/canopen_event_log.hpp"
#include "drivers/canopen/canopen_latest.hpp"
#include "drivers/canopen/canopen_valve_config.hpp"
#include "rt/driver.hpp"
#include "rt/sample.hpp"

namespace rigctl {

// What the valve says it is, read by SDO at start-up (0x1000, 0x1018).
struct ValveIdentity {
  uint32_t device_type = 0;  // low 16 bits: device profile number, 408 for a CiA 408 valve
  uint32_t vendor_id = 0;
  std::optional<uint32_t> product_code;  // 0x1018:2..4 are optional objects
  std::optional<uint32_t> revision;
  std::optional<uint32_t> serial;
};

class CanopenValve {
 public:
  // Why read_actual() flags the inputs (bits of faults()).
  enum Fault : uint32_t {
    kFaultNotRunning = 1U << 0,      // not started, start failed, or stopped
    kFaultLinkLost = 1U << 1,        // peer hung up / socket error (latched)
    kFaultHeartbeatLost = 1U << 2,   // valve heartbeat timed out (latched)
    kFaultValveReset = 1U << 3,      // boot-up while operational (latched)
    kFaultEmcy = 1U << 4,            // last EMCY had a non-zero error register
    kFaultNotOperational = 1U << 5,  // valve heartbeat reports a state other than operational
    kFaultDeviceState = 1U << 6,     // status word left DEVICE MODE ACTIVE (latched)
  };

  // The first reason read_actual() flagged the inputs in a session.
  enum class FlagReason : uint8_t {
    kNone,
    kLinkLost,
    kValveReset,
    kHeartbeatLost,      // the I/O thread saw the timeout
    kHeartbeatStale,     // the loop's clock saw it first
    kEmcy,
    kNotOperational,
    kDeviceState,
    kNoActualValue,
    kActualStale,
  };

  // Throws std::invalid_argument for an inconsistent config.
  explicit CanopenValve(CanopenValveConfig config);
  ~CanopenValve();
  CanopenValve(const CanopenValve&) = delete;
  CanopenValve& operator=(const CanopenValve&) = delete;

  // Not real-time. Opens the transport of the config (SocketCAN interface or
  // seqpacket socket path, retrying the connect until the deadline), then
  // runs the start-up sequence (header comment), so the loop's first read
  // finds a fresh actual value from a valve in DEVICE MODE ACTIVE. Throws
  // std::runtime_error naming the node and the step (an SDO abort names
  // index:subindex, the abort code and its text); the transport is closed
  // then and start() may be called again.
  void start();
  // The same on a transport the caller opened (e.g. one end of a socketpair).
  void start(CanTransport transport);
  // Not real-time: null setpoint, NMT enter pre-operational, I/O thread
  // joined, transport closed. Call it after the loop stopped using the
  // real-time API. Pre-operational rather than stopped: the valve takes no
  // more PDOs (so nothing can move the spool) but still answers SDO and sends
  // heartbeat and EMCY, so it stays observable and the next start() can
  // configure it without a power cycle.
  void stop() noexcept;

  // ---- real-time API (noexcept, no allocation, no lock) ----
  // Spool setpoint as a fraction of rated opening, clamped to [-1, 1]; NaN
  // sends the null setpoint (0). Sent at once as the setpoint RPDO with
  // control word ACTIVE. Ignored when not running.
  void write_setpoint(double fraction) noexcept;
  // The null setpoint now; the I/O thread repeats it until the next
  // write_setpoint().
  void make_safe() noexcept;
  // Writes the spool actual value (fraction, -1..1 nominal) to
  // out.value[first_index] and the pressure (Pa), if mapped, to the next
  // index; sets their out.status bits when the values must not be used (see
  // the header comment). Does nothing if the inputs would not fit.
  void read_actual(Sample& out, std::size_t first_index, int64_t now_ns) const noexcept;
  // True when read_actual() at now_ns would report valid inputs (for other
  // threads, tests: it keeps no copy of its own, so while the I/O thread is
  // inside a store it says false where the loop would go on with its copy).
  bool healthy(int64_t now_ns) const noexcept;
  static int64_t clock_ns() noexcept;

  // Not real-time: the first reason the inputs were flagged since start(),
  // in words (e.g. "canopen valve node 1: left DEVICE MODE ACTIVE: device
  // state HOLD (status word 0x000B)"); empty when they never were. Kept
  // after stop().
  std::string flag_cause() const;
  FlagReason first_flag_reason() const noexcept { return static_cast<FlagReason>(first_flag_.load(std::memory_order_acquire)); }

  // ---- not real-time ----
  // The inputs read_actual() fills, in order: the spool actual value (unit
  // "1") and, when configured, the pressure ("Pa").
  std::vector<ChannelInfo> input_channels() const;
  std::size_t input_count() const { return config_.pressure_input.empty() ? 1 : 2; }
  // Running counters and the events since the previous call (at most 64 are
  // kept; older ones are dropped and counted).
  DriverDiagnostics diagnostics();

  const CanopenValveConfig& config() const { return config_; }
  bool running() const noexcept { return running_.load(std::memory_order_acquire); }
  uint32_t faults() const noexcept { return faults_.load(std::memory_order_acquire); }
  int64_t last_valve_heartbeat_ns() const noexcept { return last_heartbeat_ns_.load(std::memory_order_acquire); }
  canopen::NmtState valve_nmt_state() const noexcept {
    return static_cast<canopen::NmtState>(valve_state_.load(std::memory_order_acquire));
  }
  // Read during the last start() (zeros before).
  ValveIdentity identity() const;
  // Counts of 100 % spool in use (the valve's 0x6311:1 or the configured one).
  int spool_full_scale() const noexcept { return spool_full_scale_; }
  // Latest decoded actual value and its receive time (count 0: none yet).
  ValveActual latest_actual() const noexcept;

 private:
  // Start-up steps, on the caller's thread: canopen_valve_startup.cpp (the
  // sequence, NMT), canopen_valve_sdo.cpp (SDO, identity, scale),
  // canopen_valve_pdos.cpp (PDO set-up), canopen_valve_device_state.cpp
  // (the walk to DEVICE MODE ACTIVE).
  CanTransport open_transport(int64_t deadline_ns);
  void start_session(CanTransport transport, int64_t deadline_ns);
  void run_startup(int64_t deadline_ns);
  void reset_communication(int64_t deadline_ns);
  void start_operational(int64_t deadline_ns);
  void sdo_write(const SdoWrite& w, int64_t deadline_ns);
  std::optional<uint32_t> sdo_read(uint16_t index, uint8_t subindex, const std::string& what, bool required,
                                   int64_t deadline_ns);
  canopen::SdoResult sdo_transfer(const std::function<std::optional<canopen::CanFrame>()>& start,
                                  const std::string& what, int64_t deadline_ns);
  void read_identity(int64_t deadline_ns);
  void read_spool_scale(int64_t deadline_ns);
  void set_spool_scale(int full_scale);
  void configure_pdos(int64_t deadline_ns);
  void set_up_pdo(const canopen::PdoSetup& setup, int64_t deadline_ns);
  canopen::PdoSetup pdo_setup(canopen::PdoDirection direction) const;  // the setpoint RPDO or the actual-value TPDO
  void walk_to_active(int64_t deadline_ns);
  // Handles frames until done(); past deadline_ns fails with "no WHAT within
  // LIMIT" (LIMIT: the start-up timeout unless given).
  void pump_until(const std::function<bool()>& done, int64_t deadline_ns, const std::string& what,
                  const std::string& limit = "");
  [[noreturn]] void fail(const std::string& what) const;

  // Frame handling (canopen_valve_io.cpp): the start-up thread, then the I/O thread.
  void io_loop();
  void service(int timeout_ms);
  void housekeeping(int64_t now_ns);
  void repeat_null_setpoint(int64_t now_ns);
  void on_frame(const canopen::CanFrame& f, int64_t now_ns);
  void on_heartbeat(const canopen::Heartbeat& hb, int64_t now_ns);
  void on_emcy(const canopen::Emcy& e);
  void on_actual(const canopen::CanFrame& f, int64_t now_ns);
  void on_sdo(const canopen::CanFrame& f, int64_t now_ns);
  void on_link_lost(CanTransport::Rx why);
  void on_device_state(uint16_t status_word);
  void count_malformed(canopen::Malformed m, const canopen::CanFrame& f);
  void send_rpdo(uint16_t control_word, double fraction) noexcept;
  FlagReason flag_reason(const ValveActual& a, bool have, int64_t now_ns) const noexcept;
  void note_flag(FlagReason why, const ValveActual& a, int64_t now_ns) const noexcept;
  void retire_transport();  // admin_mutex_ held
  void set_fault(uint32_t bits) noexcept { faults_.fetch_or(bits, std::memory_order_acq_rel); }
  void clear_fault(uint32_t bits) noexcept { faults_.fetch_and(~bits, std::memory_order_acq_rel); }
  bool send(const canopen::CanFrame& f) noexcept { return transport_.send(f); }
  std::string prefix() const;

  CanopenValveConfig config_;
  canopen::PdoMapping rpdo_map_;
  canopen::PdoMapping tpdo_map_;
  uint32_t setpoint_cob_ = 0;
  uint32_t actual_cob_ = 0;
  int64_t max_age_ns_ = 0;
  int64_t heartbeat_timeout_ns_ = 0;
  int64_t keepalive_ns_ = 0;  // the I/O thread repeats the null setpoint this often while the valve is held safe
  int spool_full_scale_ = canopen::cia408::kFullScale;

  CanTransport transport_;
  std::thread io_thread_;
  std::atomic<bool> stop_requested_{false};
  std::atomic<bool> running_{false};  // RT API active: set after start-up, cleared first in stop()

  // Protocol state: owned by whichever thread pumps frames (start-up, then I/O).
  canopen::HeartbeatConsumer consumer_;
  canopen::HeartbeatProducer producer_;
  canopen::SdoClient sdo_;
  std::optional<canopen::SdoResult> sdo_result_;
  bool link_lost_ = false;
  bool expect_operational_ = false;  // after NMT start: any other state is a fault
  uint64_t actual_count_ = 0;
  std::array<bool, canopen::kMalformedReasons> malformed_reported_{};
  bool bad_size_reported_ = false;
  uint16_t last_status_word_ = 0;
  int64_t next_keepalive_ns_ = 0;

  // Shared with the real-time loop and diagnostics().
  LatestValveActual latest_;
  // The loop's own last consistent copy (read_actual() only, the loop's
  // thread): when the I/O thread is preempted inside a store, the sequence
  // lock gives no copy for a moment, and the loop goes on with this one,
  // judged by its age like any other (stale after actual_max_age_s).
  mutable ValveActual loop_copy_{};
  std::atomic<int64_t> last_heartbeat_ns_{0};
  std::atomic<uint8_t> valve_state_{0};
  std::atomic<uint32_t> faults_{kFaultNotRunning};
  std::atomic<bool> safe_hold_{true};  // the loop holds the valve at null: the I/O thread repeats it
  // What the I/O thread saw last, for flag_cause().
  std::atomic<uint16_t> left_active_status_word_{0};
  std::atomic<uint16_t> last_emcy_code_{0};
  std::atomic<uint8_t> last_emcy_register_{0};
  // The first flag of the session (FlagReason) and what it saw.
  mutable std::atomic<uint8_t> first_flag_{0};
  mutable std::atomic<uint16_t> first_flag_status_word_{0};
  mutable std::atomic<int64_t> first_flag_age_ns_{0};
  mutable std::atomic<uint8_t> first_flag_nmt_{0};

  struct Counters {
    std::atomic<uint64_t> accepted{0}, ignored{0}, heartbeat_timeouts{0}, valve_resets{0}, emcy{0},
        sdo_aborts{0}, sdo_retries{0}, link_lost{0}, actual{0}, discarded_before_reset{0}, left_active{0},
        keepalives{0};
    std::array<std::atomic<uint64_t>, canopen::kMalformedReasons> malformed{};
  } counters_;
  // Guards replacing/closing transport_ against diagnostics() reading its
  // counters. Never taken by the real-time API (which runs only between
  // start() and stop()) nor by the I/O thread.
  mutable std::mutex admin_mutex_;
  CanTransport::Counters transport_totals_;  // of transports already closed
  ValveIdentity identity_;
  BoundedEventLog events_;
};

}  // namespace rigctl
