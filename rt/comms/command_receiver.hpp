// The rig's side of operator commands: a thread of its own that listens on
// the command channel, verifies each message (rt/comms/operator_auth.hpp), pushes
// accepted commands into a lock-free queue that the real-time loop polls,
// logs every rejection with its reason and replies on the ack channel. The
// loop only ever calls queue().try_pop(): no locks, allocation or logging
// on its side.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "rt/safety/operator_command.hpp"
#include "rt/spsc_queue.hpp"
#include "rt/comms/operator_auth.hpp"

namespace lcm {
class LCM;
struct ReceiveBuffer;
}  // namespace lcm

namespace rigctl {

// "<prefix>OPERATOR", e.g. RIGCTL_OPERATOR.
std::string default_command_channel(const std::string& channel_prefix);
// "<command channel>_ACK", e.g. RIGCTL_OPERATOR_ACK.
std::string default_ack_channel(const std::string& command_channel);

// One logged rejection (or a summary: reason "suppressed", sequence 0).
struct RejectionNote {
  int64_t utime = 0;     // the rig's wall clock when it arrived
  std::string reason;    // to_string(RejectReason), e.g. "bad_tag"
  int64_t sequence = 0;  // as received
  std::string text;      // the log line's text: reason, field at fault, sender
};

struct CommandReceiverOptions {
  std::string lcm_url;          // required: never LCM's implicit default group
  std::string channel = "RIGCTL_OPERATOR";
  std::string ack_channel;      // "": default_ack_channel(channel)
  std::string key_path;         // the service's key file (load_operator_key's checks)
  CommandPolicy policy;         // staleness window, setpoint limits
  std::size_t queue_capacity = 64;
  std::size_t max_senders = 256;
  int rejection_logs_per_second = 20;  // more in one second are summarised (a flood must not fill the disk)
  // Also called, on the receiver thread, with each rejection line it logs
  // (and each summary of those it did not): `rigctl run` writes them into
  // the event log. Same rate limit as the log. Must not throw.
  std::function<void(const RejectionNote&)> on_rejection_logged;
};

class CommandReceiver {
 public:
  // Loads the key, opens LCM and subscribes. Throws std::runtime_error with
  // the reason (key file, URL). The LCM sockets belong to the calling
  // thread's network namespace.
  explicit CommandReceiver(const CommandReceiverOptions& options);
  ~CommandReceiver();
  CommandReceiver(const CommandReceiver&) = delete;
  CommandReceiver& operator=(const CommandReceiver&) = delete;

  void start();
  void stop();  // joins the thread; idempotent

  // A command that came another way than LCM (the browser console,
  // foxglove/console): the LCM bytes of an operator_command_t, checked by
  // the same verifier and replay table, logged the same way and queued on
  // the same queue the loop reads, so there is one path into the state
  // machine. Any thread (a mutex serialises the producers; the loop's side
  // stays lock-free). The answer goes back to the caller, not on LCM.
  DecodedCommand submit(const void* data, std::size_t size);

  // Consumer side for the loop (single consumer).
  SpscQueue<OperatorCommand>& queue() { return queue_; }

  // Per reason (kNone: accepted and queued). Any thread.
  const RejectCounters& counters() const { return verifier_.counters(); }
  uint64_t acks_sent() const { return acks_sent_.load(std::memory_order_relaxed); }
  const std::string& channel() const { return channel_; }
  // The rig's key and policy (both fixed at construction): the console
  // checks its take-control claims with them (foxglove/console).
  const OperatorKey& key() const { return verifier_.key(); }
  const CommandPolicy& policy() const { return verifier_.policy(); }
  const std::string& ack_channel() const { return ack_channel_; }

 private:
  void on_message(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  // Verify, queue, log: the producer side, under producer_mu_.
  DecodedCommand accept(const void* data, std::size_t size, int64_t now_utime);
  void reply(const DecodedCommand& d, int64_t now_utime);
  void log_rejection(const DecodedCommand& d, int64_t now_utime);
  void run();

  std::string channel_;
  std::string ack_channel_;
  int logs_per_second_;
  std::function<void(const RejectionNote&)> on_rejection_logged_;
  std::mutex producer_mu_;  // the verifier, the queue's producer side, the log rate limit
  OperatorVerifier verifier_;
  SpscQueue<OperatorCommand> queue_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<uint64_t> acks_sent_{0};
  // Rejection log rate limit (receiver thread only).
  int64_t log_window_start_ = 0;
  int logged_in_window_ = 0;
  uint64_t suppressed_ = 0;
};

}  // namespace rigctl
