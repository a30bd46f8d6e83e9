#include "drivers/canopen/can_transport.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace rigctl {

using canopen::CanFrame;

namespace {

void set_nonblocking(int fd) {
  const int flags = fcntl(fd, F_GETFL, 0);
  if (flags >= 0) fcntl(fd, F_SETFL, flags | O_NONBLOCK);
}

std::string errno_text(int e) { return std::strerror(e); }

sockaddr_un unix_address(const std::string& path) {
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  if (path.empty() || path.size() >= sizeof(addr.sun_path)) {
    throw std::runtime_error("seqpacket socket path '" + path + "': must be 1 to " +
                             std::to_string(sizeof(addr.sun_path) - 1) + " characters");
  }
  std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
  return addr;
}

}  // namespace

CanTransport::CanTransport(int fd, std::string name) : fd_(fd), name_(std::move(name)), stats_(std::make_unique<Stats>()) {
  if (fd_ >= 0) set_nonblocking(fd_);
}

CanTransport::~CanTransport() { close(); }

CanTransport::CanTransport(CanTransport&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)), name_(std::move(other.name_)), stats_(std::move(other.stats_)) {}

CanTransport& CanTransport::operator=(CanTransport&& other) noexcept {
  if (this != &other) {
    close();
    fd_ = std::exchange(other.fd_, -1);
    name_ = std::move(other.name_);
    stats_ = std::move(other.stats_);
  }
  return *this;
}

bool CanTransport::send(const CanFrame& frame) noexcept {
  if (fd_ < 0) return false;
  // MSG_NOSIGNAL: a closed peer must give EPIPE, not kill the process with SIGPIPE.
  const ssize_t n = ::send(fd_, &frame, sizeof frame, MSG_DONTWAIT | MSG_NOSIGNAL);
  if (n == static_cast<ssize_t>(sizeof frame)) {
    stats_->tx.fetch_add(1, std::memory_order_relaxed);
    return true;
  }
  const int e = n < 0 ? errno : EMSGSIZE;
  stats_->last_errno.store(e, std::memory_order_relaxed);
  if (e == EAGAIN || e == EWOULDBLOCK || e == ENOBUFS) {
    stats_->tx_dropped.fetch_add(1, std::memory_order_relaxed);
  } else {
    stats_->tx_errors.fetch_add(1, std::memory_order_relaxed);
  }
  return false;
}

CanTransport::Rx CanTransport::receive(CanFrame& out, int timeout_ms) noexcept {
  if (fd_ < 0) return Rx::kError;
  pollfd p{fd_, POLLIN | POLLRDHUP, 0};
  const int r = ::poll(&p, 1, timeout_ms);
  if (r == 0) return Rx::kTimeout;
  if (r < 0) {
    if (errno == EINTR) return Rx::kTimeout;
    stats_->last_errno.store(errno, std::memory_order_relaxed);
    return Rx::kError;
  }
  const bool hup = (p.revents & (POLLHUP | POLLRDHUP)) != 0;
  if ((p.revents & POLLIN) == 0) {
    if (hup) return Rx::kHangUp;
    int so_error = 0;
    socklen_t len = sizeof so_error;
    getsockopt(fd_, SOL_SOCKET, SO_ERROR, &so_error, &len);
    stats_->last_errno.store(so_error, std::memory_order_relaxed);
    return Rx::kError;
  }
  // Room for a CAN FD frame (72 bytes) and more, so an oversized record is
  // seen at its true size and rejected instead of silently truncated.
  alignas(CanFrame) unsigned char buffer[128];
  const ssize_t n = ::recv(fd_, buffer, sizeof buffer, MSG_DONTWAIT);
  if (n < 0) {
    if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return Rx::kTimeout;
    stats_->last_errno.store(errno, std::memory_order_relaxed);
    return errno == ECONNRESET || errno == EPIPE ? Rx::kHangUp : Rx::kError;
  }
  // A zero-length read is end of stream when the peer has gone; otherwise it
  // was an empty record, which is just a record of the wrong size.
  if (n == 0 && hup) return Rx::kHangUp;
  if (n != static_cast<ssize_t>(sizeof(CanFrame))) {
    stats_->rx_bad_size.fetch_add(1, std::memory_order_relaxed);
    return Rx::kBadSize;
  }
  std::memcpy(&out, buffer, sizeof out);
  stats_->rx.fetch_add(1, std::memory_order_relaxed);
  return Rx::kFrame;
}

void CanTransport::shutdown() noexcept {
  if (fd_ >= 0) ::shutdown(fd_, SHUT_RDWR);
}

void CanTransport::close() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

CanTransport::Counters CanTransport::counters() const noexcept {
  Counters c;
  if (!stats_) return c;
  c.tx = stats_->tx.load(std::memory_order_relaxed);
  c.tx_dropped = stats_->tx_dropped.load(std::memory_order_relaxed);
  c.tx_errors = stats_->tx_errors.load(std::memory_order_relaxed);
  c.rx = stats_->rx.load(std::memory_order_relaxed);
  c.rx_bad_size = stats_->rx_bad_size.load(std::memory_order_relaxed);
  return c;
}

int CanTransport::last_errno() const noexcept {
  return stats_ ? stats_->last_errno.load(std::memory_order_relaxed) : 0;
}

CanTransport connect_seqpacket(const std::string& path) {
  const sockaddr_un addr = unix_address(path);
  const int fd = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0);
  if (fd < 0) throw std::runtime_error("seqpacket socket for '" + path + "': " + errno_text(errno));
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    const int e = errno;
    ::close(fd);
    throw std::runtime_error("cannot connect to seqpacket socket '" + path + "': " + errno_text(e));
  }
  return CanTransport(fd, "seqpacket:" + path);
}

std::pair<CanTransport, CanTransport> socketpair_seqpacket() {
  int fds[2];
  if (::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, fds) != 0) {
    throw std::runtime_error("socketpair(AF_UNIX, SOCK_SEQPACKET): " + errno_text(errno));
  }
  return {CanTransport(fds[0], "socketpair:a"), CanTransport(fds[1], "socketpair:b")};
}

SeqpacketListener::SeqpacketListener(const std::string& path) : path_(path) {
  const sockaddr_un addr = unix_address(path);
  // A socket file left by a crashed simulator would make bind() fail with
  // EADDRINUSE. Remove it only if nobody answers on it, so a live node's
  // socket is never stolen.
  struct stat st{};
  if (::lstat(path.c_str(), &st) == 0 && S_ISSOCK(st.st_mode)) {
    const int probe = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0);
    if (probe >= 0) {
      const bool live = ::connect(probe, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) == 0;
      ::close(probe);
      if (!live) ::unlink(path.c_str());
    }
  }
  fd_ = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw std::runtime_error("seqpacket socket for '" + path + "': " + errno_text(errno));
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0 || ::listen(fd_, 4) != 0) {
    const int e = errno;
    ::close(fd_);
    fd_ = -1;
    throw std::runtime_error("cannot listen on seqpacket socket '" + path + "': " + errno_text(e));
  }
  set_nonblocking(fd_);
}

SeqpacketListener::~SeqpacketListener() {
  if (fd_ >= 0) {
    ::close(fd_);
    ::unlink(path_.c_str());
  }
}

SeqpacketListener::SeqpacketListener(SeqpacketListener&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)), path_(std::move(other.path_)) {}

std::optional<CanTransport> SeqpacketListener::accept(int timeout_ms) {
  pollfd p{fd_, POLLIN, 0};
  if (::poll(&p, 1, timeout_ms) <= 0 || (p.revents & POLLIN) == 0) return std::nullopt;
  const int fd = ::accept4(fd_, nullptr, nullptr, SOCK_CLOEXEC);
  if (fd < 0) return std::nullopt;
  return CanTransport(fd, "seqpacket:" + path_ + " (accepted)");
}

}  // namespace rigctl
