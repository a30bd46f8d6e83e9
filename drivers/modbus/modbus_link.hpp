// The client end of one Modbus connection (TCP or RTU): a libmodbus context
// with the project's timeout and error-recovery policy, requests by read or
// write block, and every failure classified. Used by the I/O thread only;
// not thread-safe.
#pragma once

#include <string>

#include "drivers/modbus/modbus_codec.hpp"
#include "drivers/modbus/modbus_daq_config.hpp"
#include "drivers/modbus/modbus_write_plan.hpp"

struct _modbus;  // libmodbus's modbus_t, kept out of this header

namespace rigctl {

enum class ModbusErrorKind {
  kNone,
  kTimeout,    // no (complete) reply within the response timeout; the link may be fine
  kException,  // the device answered with a Modbus exception code; the link is fine
  kProtocol,   // a reply that does not fit the request (late reply, bad CRC, wrong length)
  kLink,       // the connection or port failed (reset, closed, I/O error): reconnect
};

// errno as libmodbus leaves it (its own codes included) -> kind.
ModbusErrorKind classify_modbus_error(int error) noexcept;
// modbus_strerror(), e.g. "Illegal data address", "Connection timed out".
std::string modbus_error_text(int error);
// The text of a Modbus exception code (1..11), as modbus_error_text gives it.
std::string modbus_exception_text(int code);
// "reading input registers 0-7 of unit 1", "writing holding registers 0-1 of unit 2".
std::string describe_request(bool write, RegisterType type, int unit_id, int address, int count);

struct ModbusResult {
  ModbusErrorKind kind = ModbusErrorKind::kNone;
  int error = 0;  // errno of the failure
  bool ok() const noexcept { return kind == ModbusErrorKind::kNone; }
};

class ModbusLink {
 public:
  // Allocates the context; throws std::runtime_error naming the endpoint when
  // libmodbus refuses the parameters. Opens nothing yet.
  explicit ModbusLink(const ModbusConnection& connection);
  ~ModbusLink();
  ModbusLink(const ModbusLink&) = delete;
  ModbusLink& operator=(const ModbusLink&) = delete;

  // Opens the socket or serial port: 0, or the errno of the failure. A TCP
  // connect waits at most connect_timeout_s().
  int open();
  void close() noexcept;
  bool is_open() const noexcept { return open_; }

  ModbusResult read(const ReadBlock& block, uint16_t* dest) noexcept;
  // FC 6 for a single register (what the simplest modules support), FC 16 otherwise.
  ModbusResult write(const WriteBlock& block, const uint16_t* src) noexcept;
  // After a timeout or a mismatched reply: discards everything the device
  // sends during the next response timeout. A bare flush is not enough: after
  // a late reply was taken for the next request's, that request's own reply
  // is usually still on its way; flushed too early, it would be taken for
  // the request after, and the connection would stay one reply behind for
  // good. Costs at most one response timeout, only after an error.
  void drain() noexcept;

  const std::string& endpoint() const noexcept { return endpoint_; }
  double connect_timeout_s() const noexcept;

 private:
  ModbusResult check(int rc, int expected) noexcept;
  void before_request(int unit_id) noexcept;

  ModbusConnection connection_;
  std::string endpoint_;
  _modbus* ctx_ = nullptr;
  bool open_ = false;
};

}  // namespace rigctl
