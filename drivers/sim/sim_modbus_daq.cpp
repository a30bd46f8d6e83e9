#include "drivers/sim/sim_modbus_daq.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace rigctl {

namespace {

int64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

struct Range {
  int first = 65536;
  int last = -1;
  void add(const ModbusPoint& p) {
    first = std::min(first, p.address);
    last = std::max(last, p.address + register_count(p.format) - 1);
  }
  unsigned start() const { return last < 0 ? 0u : static_cast<unsigned>(first); }
  unsigned count() const { return last < 0 ? 0u : static_cast<unsigned>(last - first + 1); }
};

ModbusDaqConfig checked(ModbusDaqConfig c) {
  validate(c);
  if (c.connection.transport == ModbusTransport::kRtu) {
    for (const auto* list : {&c.inputs, &c.outputs}) {
      for (const auto& ch : *list) {
        const int first = c.inputs.empty() ? c.outputs.front().point.unit_id : c.inputs.front().point.unit_id;
        if (ch.point.unit_id != first) {
          throw std::invalid_argument("simulated modbus DAQ: an RTU port is one slave; channel " + ch.name +
                                      " is on unit " + std::to_string(ch.point.unit_id) + ", not " +
                                      std::to_string(first));
        }
      }
    }
  }
  return c;
}

}  // namespace

SimModbusDaq::SimModbusDaq(ModbusDaqConfig config)
    : config_(checked(std::move(config))), endpoint_(endpoint_name(config_.connection)),
      port_(config_.connection.port), input_states_(config_.inputs.size()) {
  std::map<int, std::pair<Range, Range>> ranges;  // unit -> (input registers, holding registers)
  for (const auto* list : {&config_.inputs, &config_.outputs}) {
    for (const auto& ch : *list) {
      auto& r = ranges[ch.point.unit_id];
      (ch.point.type == RegisterType::kInputRegister ? r.first : r.second).add(ch.point);
    }
  }
  for (const auto& [unit, r] : ranges) {
    modbus_mapping_t* m = modbus_mapping_new_start_address(0, 0, 0, 0, r.second.start(), r.second.count(),
                                                           r.first.start(), r.first.count());
    if (m == nullptr) throw std::runtime_error("simulated modbus DAQ: cannot allocate the register map");
    mappings_[unit] = m;
  }
  std::lock_guard lock(mutex_);
  for (std::size_t i = 0; i < config_.inputs.size(); ++i) encode_input(i, config_.inputs[i].calibration.to_raw(0.0));
  for (const auto& ch : config_.outputs) {
    (void)encode_registers(ch.calibration.to_raw(ch.safe), ch.point.format, ch.point.order, registers(ch.point));
  }
}

SimModbusDaq::~SimModbusDaq() {
  stop();
  for (auto& [unit, m] : mappings_) modbus_mapping_free(m);
}

uint16_t* SimModbusDaq::registers(const ModbusPoint& p) const {
  modbus_mapping_t* m = mappings_.at(p.unit_id);
  if (p.type == RegisterType::kInputRegister) return m->tab_input_registers + (p.address - m->start_input_registers);
  return m->tab_registers + (p.address - m->start_registers);
}

void SimModbusDaq::encode_input(std::size_t i, double raw) {
  const ModbusPoint& p = config_.inputs[i].point;
  if (std::isnan(raw) && p.format == DataFormat::kFloat32) {
    split_registers(0x7FC00000u, p.order, registers(p));  // a quiet NaN, as a failed module might report
    return;
  }
  (void)encode_registers(raw, p.format, p.order, registers(p));  // saturates like an ADC; NaN leaves them
}

void SimModbusDaq::start() {
  if (thread_.joinable()) throw std::logic_error("simulated modbus DAQ " + endpoint_ + ": already started");
  const ModbusConnection& k = config_.connection;
  auto fail = [&](const std::string& what) {
    const std::string error = modbus_strerror(errno);
    if (listen_fd_ >= 0) ::close(listen_fd_);
    listen_fd_ = -1;
    if (ctx_ != nullptr) modbus_free(ctx_);
    ctx_ = nullptr;
    throw std::runtime_error("simulated modbus DAQ " + endpoint_ + ": " + what + ": " + error);
  };
  if (k.transport == ModbusTransport::kTcp) {
    ctx_ = modbus_new_tcp(k.host.c_str(), k.port);
    if (ctx_ == nullptr) fail("cannot create the context");
    listen_fd_ = modbus_tcp_listen(ctx_, 8);
    if (listen_fd_ < 0) fail("cannot listen");
    sockaddr_in addr{};
    socklen_t len = sizeof addr;
    if (getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len) != 0) fail("getsockname");
    port_ = ntohs(addr.sin_port);
    endpoint_ = k.host + ":" + std::to_string(port_);
  } else {
    ctx_ = modbus_new_rtu(k.device.c_str(), k.baud, k.parity, k.data_bits, k.stop_bits);
    if (ctx_ == nullptr) fail("cannot create the context");
    const auto& first = config_.inputs.empty() ? config_.outputs.front() : config_.inputs.front();
    modbus_set_slave(ctx_, first.point.unit_id);
    if (modbus_connect(ctx_) != 0) fail("cannot open the serial port");
  }
  if (pipe2(wake_fds_, O_CLOEXEC | O_NONBLOCK) != 0) fail("pipe");
  stop_requested_ = false;
  thread_ = std::thread([this] { serve(); });
}

void SimModbusDaq::stop() {
  if (!thread_.joinable()) return;
  stop_requested_ = true;
  wake();
  thread_.join();
  for (int fd : clients_) ::close(fd);
  clients_.clear();
  if (listen_fd_ >= 0) ::close(listen_fd_);
  listen_fd_ = -1;
  if (config_.connection.transport == ModbusTransport::kRtu) modbus_close(ctx_);
  modbus_free(ctx_);
  ctx_ = nullptr;
  for (int& fd : wake_fds_) {
    ::close(fd);
    fd = -1;
  }
}

ModbusDaqConfig SimModbusDaq::client_config() const {
  ModbusDaqConfig c = config_;
  c.connection.port = port_;
  return c;
}

void SimModbusDaq::set_inputs(const double* si, std::size_t n) {
  std::lock_guard lock(mutex_);
  for (std::size_t i = 0; i < std::min(n, config_.inputs.size()); ++i) {
    if (input_states_[i].stuck || input_states_[i].forced) continue;
    encode_input(i, config_.inputs[i].calibration.to_raw(si[i]));
  }
}

void SimModbusDaq::outputs(double* si) const {
  std::lock_guard lock(mutex_);
  for (std::size_t i = 0; i < config_.outputs.size(); ++i) {
    const ModbusChannel& ch = config_.outputs[i];
    si[i] = ch.calibration.to_si(decode_registers(registers(ch.point), ch.point.format, ch.point.order));
  }
}

// --- Faults

void SimModbusDaq::drop_connections(double refuse_for_s) {
  if (config_.connection.transport != ModbusTransport::kTcp) {
    throw std::logic_error("simulated modbus DAQ: drop_connections is for TCP");
  }
  refuse_until_ns_ = monotonic_ns() + static_cast<int64_t>(refuse_for_s * 1e9);
  drop_requested_ = true;
  wake();
}

void SimModbusDaq::set_silent(bool silent) { silent_ = silent; }
void SimModbusDaq::set_reply_delay(double delay_s) { reply_delay_s_ = std::max(0.0, delay_s); }

void SimModbusDaq::add_exception(const ModbusExceptionFault& fault) {
  if (fault.code < 1 || fault.code >= MODBUS_EXCEPTION_MAX) {
    throw std::invalid_argument("modbus exception code must be in 1.." + std::to_string(MODBUS_EXCEPTION_MAX - 1));
  }
  std::lock_guard lock(mutex_);
  exceptions_.push_back(fault);
}

void SimModbusDaq::clear_exceptions() {
  std::lock_guard lock(mutex_);
  exceptions_.clear();
}

void SimModbusDaq::set_stuck(std::size_t input, bool stuck) {
  std::lock_guard lock(mutex_);
  input_states_.at(input).stuck = stuck;
}

void SimModbusDaq::force_raw(std::size_t input, double raw) {
  std::lock_guard lock(mutex_);
  InputState& s = input_states_.at(input);
  if (std::isnan(raw) && config_.inputs[input].point.format != DataFormat::kFloat32) {
    throw std::invalid_argument("force_raw: an integer register cannot hold NaN");
  }
  s.forced = true;
  s.forced_raw = raw;
  encode_input(input, raw);
}

void SimModbusDaq::release_raw(std::size_t input) {
  std::lock_guard lock(mutex_);
  input_states_.at(input).forced = false;
}

void SimModbusDaq::clear_faults() {
  set_silent(false);
  set_reply_delay(0.0);
  refuse_until_ns_ = 0;
  std::lock_guard lock(mutex_);
  exceptions_.clear();
  for (auto& s : input_states_) s = {};
}

// --- Server thread

void SimModbusDaq::wake() noexcept {
  const char c = 1;
  [[maybe_unused]] const auto n = ::write(wake_fds_[1], &c, 1);
}

bool SimModbusDaq::sleep_or_wake(double seconds) noexcept {
  const int64_t until = monotonic_ns() + static_cast<int64_t>(seconds * 1e9);
  for (int64_t now = monotonic_ns(); now < until && !stop_requested_; now = monotonic_ns()) {
    pollfd p{wake_fds_[0], POLLIN, 0};
    ::poll(&p, 1, static_cast<int>((until - now + 999999) / 1000000));
    char buf[64];
    while (::read(wake_fds_[0], buf, sizeof buf) > 0) {
    }
  }
  return !stop_requested_;
}

void SimModbusDaq::handle(const uint8_t* req, int length) noexcept {
  ++requests_;
  if (silent_) return;
  const double delay = reply_delay_s_;
  if (delay > 0.0 && !sleep_or_wake(delay)) return;

  const int h = modbus_get_header_length(ctx_);
  const int unit = req[h - 1];
  const int function = req[h];
  const int address = (req[h + 1] << 8) | req[h + 2];
  int count = 1;
  RegisterType type = RegisterType::kHoldingRegister;
  switch (function) {
    case MODBUS_FC_READ_INPUT_REGISTERS:
      type = RegisterType::kInputRegister;
      [[fallthrough]];
    case MODBUS_FC_READ_HOLDING_REGISTERS:
    case MODBUS_FC_WRITE_MULTIPLE_REGISTERS:
      count = (req[h + 3] << 8) | req[h + 4];
      break;
    default:
      break;  // FC 6 writes one holding register; others are left to modbus_reply
  }
  if (exchange_hook_ && type == RegisterType::kInputRegister && function == MODBUS_FC_READ_INPUT_REGISTERS &&
      !config_.inputs.empty()) {
    const ModbusPoint& first = config_.inputs.front().point;
    if (first.type == RegisterType::kInputRegister && unit == first.unit_id && address <= first.address &&
        first.address < address + count) {
      exchange_hook_();
    }
  }

  std::lock_guard lock(mutex_);
  for (const auto& f : exceptions_) {
    if ((f.unit_id < 0 || f.unit_id == unit) && f.type == type && address <= f.last && address + count - 1 >= f.first) {
      modbus_reply_exception(ctx_, req, static_cast<unsigned>(f.code));
      ++replies_;
      return;
    }
  }
  const auto m = mappings_.find(unit);
  if (m == mappings_.end()) {
    // What a gateway answers for a unit it cannot reach.
    modbus_reply_exception(ctx_, req, MODBUS_EXCEPTION_GATEWAY_TARGET);
  } else {
    const int replied = modbus_reply(ctx_, req, length, m->second);  // out-of-map addresses get "illegal data address"
    if (replied > 0 && (function == MODBUS_FC_WRITE_SINGLE_REGISTER || function == MODBUS_FC_WRITE_MULTIPLE_REGISTERS)) {
      ++writes_;
    }
  }
  ++replies_;
}

void SimModbusDaq::serve() noexcept {
  const bool tcp = config_.connection.transport == ModbusTransport::kTcp;
  uint8_t request[MODBUS_TCP_MAX_ADU_LENGTH];
  std::vector<pollfd> fds;
  while (!stop_requested_) {
    if (drop_requested_.exchange(false)) {
      for (int fd : clients_) ::close(fd);
      clients_.clear();
    }
    fds.clear();
    fds.push_back({wake_fds_[0], POLLIN, 0});
    fds.push_back({tcp ? listen_fd_ : modbus_get_socket(ctx_), POLLIN, 0});
    for (int fd : clients_) fds.push_back({fd, POLLIN, 0});
    if (::poll(fds.data(), fds.size(), -1) < 0) continue;  // EINTR
    if (fds[0].revents != 0) {
      char buf[64];
      while (::read(wake_fds_[0], buf, sizeof buf) > 0) {
      }
    }
    if (!tcp) {
      if (fds[1].revents == 0) continue;
      const int rc = modbus_receive(ctx_, request);
      if (rc > 0) {
        handle(request, rc);
      } else if (rc < 0) {
        modbus_flush(ctx_);  // a broken frame; the client will time out and retry
        if (fds[1].revents & (POLLHUP | POLLERR)) sleep_or_wake(0.01);  // peer gone: do not spin
      }
      continue;
    }
    if (fds[1].revents & POLLIN) {
      const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
      if (fd >= 0) {
        if (monotonic_ns() < refuse_until_ns_) {
          ::close(fd);
        } else {
          const int one = 1;
          setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
          clients_.push_back(fd);
          ++connections_;
        }
      }
    }
    for (std::size_t i = 2; i < fds.size(); ++i) {
      if (fds[i].revents == 0) continue;
      modbus_set_socket(ctx_, fds[i].fd);
      const int rc = modbus_receive(ctx_, request);
      if (rc > 0) handle(request, rc);
      if (rc < 0) {  // the client closed, or sent garbage: forget it
        ::close(fds[i].fd);
        clients_.erase(std::find(clients_.begin(), clients_.end(), fds[i].fd));
      }
    }
  }
}

}  // namespace rigctl
