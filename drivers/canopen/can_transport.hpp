// CAN frame I/O on a file descriptor: one `struct can_frame` (16 bytes) per
// read or write. In production the fd is a SocketCAN CAN_RAW socket
// (drivers/canopen/socketcan.hpp); in tests and in the simulated rig it is a
// SOCK_SEQPACKET unix socket, which keeps the same one-frame-per-record
// semantics (the development and CI kernel has no CAN at all:
// docs/hardware.md, "What was tested where").
//
// send() never blocks: the real-time loop may call it. A full socket buffer
// (EAGAIN, or ENOBUFS from a CAN driver whose tx queue is full) drops the
// frame and counts it, as a real bus adapter would under overload.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "drivers/canopen/protocol/can_frame.hpp"

namespace rigctl {

class CanTransport {
 public:
  enum class Rx : uint8_t {
    kFrame,    // `out` holds one frame
    kTimeout,  // nothing within the timeout (or interrupted by a signal)
    kHangUp,   // the peer closed the connection (seqpacket) or the socket was shut down
    kBadSize,  // a record that is not one struct can_frame: counted and dropped
    kError,    // any other socket error (errno in last_errno()); the link is unusable
  };

  struct Counters {
    uint64_t tx = 0;           // frames sent
    uint64_t tx_dropped = 0;   // not sent: socket buffer full (EAGAIN/ENOBUFS)
    uint64_t tx_errors = 0;    // not sent: any other error (peer gone, interface down)
    uint64_t rx = 0;           // frames received
    uint64_t rx_bad_size = 0;  // records of the wrong size
  };

  CanTransport() = default;  // closed
  // Takes ownership of `fd` and makes it non-blocking; `name` is for messages.
  CanTransport(int fd, std::string name);
  ~CanTransport();
  CanTransport(CanTransport&& other) noexcept;
  CanTransport& operator=(CanTransport&& other) noexcept;
  CanTransport(const CanTransport&) = delete;
  CanTransport& operator=(const CanTransport&) = delete;

  bool is_open() const noexcept { return fd_ >= 0; }
  int fd() const noexcept { return fd_; }
  const std::string& name() const noexcept { return name_; }

  // Real-time safe: one non-blocking send syscall, no allocation. May be
  // called from two threads at once (each record is written atomically).
  bool send(const canopen::CanFrame& frame) noexcept;
  // Waits up to timeout_ms (0: just check, -1: forever) for one record.
  Rx receive(canopen::CanFrame& out, int timeout_ms) noexcept;

  // Shuts both directions down: the peer sees a hang-up, our receive()
  // returns kHangUp, send() fails. The fd stays valid until close().
  void shutdown() noexcept;
  void close() noexcept;

  Counters counters() const noexcept;
  int last_errno() const noexcept;

 private:
  struct Stats {
    std::atomic<uint64_t> tx{0}, tx_dropped{0}, tx_errors{0}, rx{0}, rx_bad_size{0};
    std::atomic<int> last_errno{0};
  };
  int fd_ = -1;
  std::string name_;
  std::unique_ptr<Stats> stats_;  // on the heap so the transport stays movable
};

// Client side of a SOCK_SEQPACKET unix socket at `path`. Throws
// std::runtime_error naming the path and the reason.
CanTransport connect_seqpacket(const std::string& path);

// Both ends of a connected SOCK_SEQPACKET socketpair (tests).
std::pair<CanTransport, CanTransport> socketpair_seqpacket();

// A listening SOCK_SEQPACKET unix socket: the simulated valve node's side.
// The socket file is removed again by the destructor.
class SeqpacketListener {
 public:
  explicit SeqpacketListener(const std::string& path);  // throws std::runtime_error
  ~SeqpacketListener();
  SeqpacketListener(SeqpacketListener&& other) noexcept;
  SeqpacketListener& operator=(SeqpacketListener&&) = delete;
  SeqpacketListener(const SeqpacketListener&) = delete;
  SeqpacketListener& operator=(const SeqpacketListener&) = delete;

  // One incoming connection, or nullopt when none came within timeout_ms.
  std::optional<CanTransport> accept(int timeout_ms);
  const std::string& path() const { return path_; }

 private:
  int fd_ = -1;
  std::string path_;
};

inline SeqpacketListener listen_seqpacket(const std::string& path) { return SeqpacketListener(path); }

}  // namespace rigctl
