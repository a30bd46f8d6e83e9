// Timeout and recovery policy (libmodbus 3.1.6), and why:
//
// * Response timeout = config response_timeout_s (e.g. 2 ms on loopback, a
//   few ms on a LAN). libmodbus's default of 500 ms would let one lost reply
//   hold the I/O thread for 200 loop periods.
// * Byte timeout disabled (0, 0). With a byte timeout set, the response
//   timeout only bounds the FIRST byte and every further chunk may take up to
//   the byte timeout (default 500 ms) again. Disabled, the response timeout
//   bounds the whole reply, so one request costs at most response_timeout_s
//   and a cycle at most (requests x response_timeout_s). On RTU the timeout
//   must therefore cover the reply's transmission time at the baud rate (the
//   config reader checks this) plus the module's turnaround.
// * Error recovery NONE. MODBUS_ERROR_RECOVERY_LINK retries a failed send in
//   an endless close/sleep/connect loop (the thread could never be stopped)
//   and sleeps a response timeout before each flush; PROTOCOL also sleeps.
//   The I/O thread instead drains the line for one response timeout after a
//   timeout or a mismatched reply (see drain()) and reconnects on its own
//   schedule (ModbusDaq, reconnect_interval_s), so every call here returns
//   within a bounded time.
// * RTU: the input buffer is flushed before every request. A serial reply has
//   no transaction id, so a reply that arrived after its timeout would be
//   taken for the next identical request's. (One that arrives while the next
//   request is already waiting still cannot be told apart: keep the response
//   timeout above the module's worst turnaround.) TCP matches transaction ids.
// * The TCP connect uses the response timeout slot of the context (libmodbus
//   has no separate one): it is raised to connect_timeout_s() for the
//   connect and put back after.
#include "drivers/modbus/modbus_link.hpp"

#include <modbus/modbus.h>

#include <poll.h>
#include <time.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <stdexcept>

namespace rigctl {

namespace {

void set_response_timeout(modbus_t* ctx, double s) {
  const auto us = static_cast<uint32_t>(std::max(1.0, std::round(s * 1e6)));
  modbus_set_response_timeout(ctx, us / 1000000u, us % 1000000u);
}

}  // namespace

ModbusErrorKind classify_modbus_error(int e) noexcept {
  if (e == ETIMEDOUT) return ModbusErrorKind::kTimeout;
  if (e > MODBUS_ENOBASE && e < MODBUS_ENOBASE + MODBUS_EXCEPTION_MAX) return ModbusErrorKind::kException;
  switch (e) {
    case EMBBADCRC:
    case EMBBADDATA:
    case EMBBADEXC:
    case EMBUNKEXC:
    case EMBMDATA:
    case EMBBADSLAVE:
      return ModbusErrorKind::kProtocol;
    default:
      return ModbusErrorKind::kLink;  // ECONNRESET, EPIPE, EBADF, EIO, ...
  }
}

std::string modbus_error_text(int e) { return modbus_strerror(e); }

std::string modbus_exception_text(int code) { return modbus_strerror(MODBUS_ENOBASE + code); }

std::string describe_request(bool write, RegisterType type, int unit_id, int address, int count) {
  return std::string(write ? "writing " : "reading ") +
         (type == RegisterType::kInputRegister ? "input registers " : "holding registers ") +
         std::to_string(address) + "-" + std::to_string(address + count - 1) + " of unit " + std::to_string(unit_id);
}

ModbusLink::ModbusLink(const ModbusConnection& c) : connection_(c), endpoint_(endpoint_name(c)) {
  if (c.transport == ModbusTransport::kTcp) {
    ctx_ = modbus_new_tcp_pi(c.host.c_str(), std::to_string(c.port).c_str());
  } else {
    ctx_ = modbus_new_rtu(c.device.c_str(), c.baud, c.parity, c.data_bits, c.stop_bits);
  }
  if (ctx_ == nullptr) {
    throw std::runtime_error("modbus " + endpoint_ + ": cannot create a libmodbus context: " + modbus_strerror(errno));
  }
  modbus_set_error_recovery(ctx_, MODBUS_ERROR_RECOVERY_NONE);
  modbus_set_byte_timeout(ctx_, 0, 0);
  set_response_timeout(ctx_, c.response_timeout_s);
}

ModbusLink::~ModbusLink() {
  close();
  modbus_free(ctx_);
}

double ModbusLink::connect_timeout_s() const noexcept {
  // Long enough for a real network's handshake, short enough that stop()
  // never waits long for a connect to a dead host.
  return std::clamp(connection_.reconnect_interval_s, connection_.response_timeout_s, 1.0);
}

int ModbusLink::open() {
  close();
  set_response_timeout(ctx_, connect_timeout_s());
  const int rc = modbus_connect(ctx_);
  const int error = errno;
  set_response_timeout(ctx_, connection_.response_timeout_s);
  if (rc == -1) return error == 0 ? EIO : error;
  open_ = true;
  modbus_flush(ctx_);  // a serial line may hold bytes from before
  return 0;
}

void ModbusLink::close() noexcept {
  if (open_) modbus_close(ctx_);
  open_ = false;
}

ModbusResult ModbusLink::check(int rc, int expected) noexcept {
  if (rc == expected) return {};
  const int error = rc == -1 ? errno : EMBBADDATA;  // a short read is a malformed reply
  return {classify_modbus_error(error), error};
}

ModbusResult ModbusLink::read(const ReadBlock& b, uint16_t* dest) noexcept {
  if (!open_) return {ModbusErrorKind::kLink, ENOTCONN};
  before_request(b.unit_id);
  const int rc = b.type == RegisterType::kInputRegister ? modbus_read_input_registers(ctx_, b.address, b.count, dest)
                                                       : modbus_read_registers(ctx_, b.address, b.count, dest);
  return check(rc, b.count);
}

ModbusResult ModbusLink::write(const WriteBlock& b, const uint16_t* src) noexcept {
  if (!open_) return {ModbusErrorKind::kLink, ENOTCONN};
  before_request(b.unit_id);
  if (b.count == 1) return check(modbus_write_register(ctx_, b.address, src[0]), 1);
  return check(modbus_write_registers(ctx_, b.address, b.count, src), b.count);
}

void ModbusLink::before_request(int unit_id) noexcept {
  modbus_set_slave(ctx_, unit_id);
  if (connection_.transport == ModbusTransport::kRtu) modbus_flush(ctx_);
}

void ModbusLink::drain() noexcept {
  if (!open_) return;
  modbus_flush(ctx_);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(connection_.response_timeout_s);
  pollfd p{modbus_get_socket(ctx_), POLLIN, 0};
  for (;;) {
    const auto left = std::chrono::ceil<std::chrono::microseconds>(deadline - std::chrono::steady_clock::now()).count();
    if (left <= 0) return;
    const timespec ts{static_cast<time_t>(left / 1000000), static_cast<long>(left % 1000000) * 1000};
    p.revents = 0;
    const int rc = ppoll(&p, 1, &ts, nullptr);
    if (rc < 0 && errno == EINTR) continue;
    if (rc <= 0 || (p.revents & (POLLERR | POLLHUP | POLLNVAL)) != 0) return;  // quiet, or broken: the next request tells
    modbus_flush(ctx_);
  }
}

}  // namespace rigctl
