// The simulated DAQ module on the far side of the wire: a real libmodbus
// server (TCP, or RTU on a tty) with the same register map as the client's
// config. Its input registers are the sensors (the plant's SI values with the
// config's calibration applied in reverse); its holding registers take the
// analogue output the client writes. Faults can be injected from any thread,
// to test the client against what real modules and networks do.
//
// One server thread answers every request: poll() over the listening socket,
// the clients' sockets (any number; a reconnecting client is simply a new
// one) and a wake-up pipe, then modbus_receive / modbus_reply (or
// modbus_reply_exception). Register contents are guarded by a mutex shared
// with set_inputs()/outputs(): this is test and HIL code, not the rig's loop.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "drivers/modbus/modbus_daq_config.hpp"

struct _modbus;
struct _modbus_mapping_t;

namespace rigctl {

// Answer requests that touch [first, last] of a table with a Modbus exception.
struct ModbusExceptionFault {
  int unit_id = -1;  // -1: every unit
  RegisterType type = RegisterType::kInputRegister;
  int first = 0;
  int last = 65535;
  int code = 0x02;  // 0x02 illegal data address, 0x04 server device failure, ... (1..11)
};

class SimModbusDaq {
 public:
  // Validates the config (std::invalid_argument). RTU: every channel on one
  // unit id (one serial port is one slave). Registers start at the raw value
  // of SI 0 for inputs and of the safe value for outputs.
  explicit SimModbusDaq(ModbusDaqConfig config);
  ~SimModbusDaq();  // stop()
  SimModbusDaq(const SimModbusDaq&) = delete;
  SimModbusDaq& operator=(const SimModbusDaq&) = delete;

  // TCP: listens on host:port (port 0: a free port, see port()). RTU: opens
  // the device. Starts the server thread. Throws std::runtime_error naming
  // the endpoint.
  void start();
  void stop();  // idempotent

  // Called on the server thread for every request that reads the first
  // input's registers, before it is answered (the hook may call
  // set_inputs): `rigctl rig-sim --lock-step` steps its plant there. Set it
  // before start().
  void set_exchange_hook(std::function<void()> hook) { exchange_hook_ = std::move(hook); }

  int port() const noexcept { return port_; }            // TCP: the bound port, after start()
  const std::string& endpoint() const noexcept { return endpoint_; }
  // The config with the bound port filled in: what a client should use.
  ModbusDaqConfig client_config() const;

  // Plant side: SI values in input order (n <= input count). Calibrated in
  // reverse and encoded (saturating like an ADC); NaN leaves the registers.
  void set_inputs(const double* si, std::size_t n);
  // The outputs the client wrote, decoded and calibrated to SI, output order.
  void outputs(double* si) const;

  // --- Faults (thread-safe; each one until cleared unless said otherwise)
  // TCP only: closes every client connection now, and for refuse_for_s
  // closes new ones as soon as they are accepted.
  void drop_connections(double refuse_for_s = 0.0);
  // Reads requests but never replies.
  void set_silent(bool silent);
  // Delays every reply by delay_s.
  void set_reply_delay(double delay_s);
  void add_exception(const ModbusExceptionFault& fault);
  void clear_exceptions();
  // Freezes an input's registers at their present raw value.
  void set_stuck(std::size_t input, bool stuck);
  // Forces an input's raw register value (e.g. 32767, the ADC rail; NaN on a
  // float32 input writes a NaN pattern). Overrides set_inputs until released.
  void force_raw(std::size_t input, double raw);
  void release_raw(std::size_t input);
  void clear_faults();

  // Statistics for tests.
  int64_t requests() const noexcept { return requests_.load(); }       // received
  int64_t replies() const noexcept { return replies_.load(); }         // answered (data or exception)
  int64_t connections() const noexcept { return connections_.load(); }  // TCP: accepted and kept
  // Writes to holding registers answered: an output watchdog (rig-sim) counts time since the last.
  int64_t writes() const noexcept { return writes_.load(); }

 private:
  struct InputState {
    bool stuck = false;
    bool forced = false;
    double forced_raw = 0.0;
  };

  uint16_t* registers(const ModbusPoint& p) const;  // mutex_ held
  void encode_input(std::size_t i, double raw);      // mutex_ held
  void serve() noexcept;
  void handle(const uint8_t* request, int length) noexcept;
  bool sleep_or_wake(double seconds) noexcept;  // false when woken to stop
  void wake() noexcept;

  ModbusDaqConfig config_;
  std::string endpoint_;
  int port_ = 0;
  _modbus* ctx_ = nullptr;
  int listen_fd_ = -1;
  int wake_fds_[2] = {-1, -1};
  std::vector<int> clients_;  // server thread only
  std::function<void()> exchange_hook_;
  std::thread thread_;
  std::atomic<bool> stop_requested_{false};

  mutable std::mutex mutex_;  // registers, input states, exception faults
  std::map<int, _modbus_mapping_t*> mappings_;  // by unit id
  std::vector<InputState> input_states_;
  std::vector<ModbusExceptionFault> exceptions_;

  std::atomic<bool> silent_{false};
  std::atomic<double> reply_delay_s_{0.0};
  std::atomic<bool> drop_requested_{false};
  std::atomic<int64_t> refuse_until_ns_{0};
  std::atomic<int64_t> requests_{0}, replies_{0}, connections_{0}, writes_{0};
};

}  // namespace rigctl
