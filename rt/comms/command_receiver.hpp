// The rig's side of operator commands over LCM: a thread of its own that
// listens on the command channel, hands each message to the command intake
// (rt/comms/command_intake.hpp: the verifier, the queue the real-time loop
// polls, the counters, the rate-limited rejection log) and replies on the
// ack channel. The loop only ever calls queue().try_pop(): no locks,
// allocation or logging on its side.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "rt/comms/command_intake.hpp"
#include "rt/comms/operator_auth.hpp"
#include "rt/safety/operator_command.hpp"
#include "rt/spsc_queue.hpp"

namespace lcm {
class LCM;
struct ReceiveBuffer;
}  // namespace lcm

namespace rigctl {

// "<prefix>OPERATOR", e.g. RIGCTL_OPERATOR.
std::string default_command_channel(const std::string& channel_prefix);
// "<command channel>_ACK", e.g. RIGCTL_OPERATOR_ACK.
std::string default_ack_channel(const std::string& command_channel);

struct CommandReceiverOptions {
  std::string lcm_url;          // required: never LCM's implicit default group
  std::string channel = "RIGCTL_OPERATOR";
  std::string ack_channel;      // "": default_ack_channel(channel)
  std::string key_path;         // the service's key file (load_operator_key's checks)
  CommandPolicy policy;         // staleness window, setpoint limits (not_before_utime: set to the receiver's start)
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

  // Commands that come another way than LCM (the browser console,
  // foxglove/console) go to the same intake: the same verifier and replay
  // table, log, counters and queue, so there is one path into the state
  // machine. The answer goes back to the caller, not on LCM.
  CommandIntake& intake() { return intake_; }
  DecodedCommand submit(const void* data, std::size_t size);

  // Consumer side for the loop (single consumer).
  SpscQueue<OperatorCommand>& queue() { return intake_.queue(); }

  // Per reason (kNone: accepted and queued). Any thread.
  const RejectCounters& counters() const { return intake_.counters(); }
  uint64_t acks_sent() const { return acks_sent_.load(std::memory_order_relaxed); }
  const std::string& channel() const { return channel_; }
  const OperatorKey& key() const { return intake_.key(); }
  const CommandPolicy& policy() const { return intake_.policy(); }
  const std::string& ack_channel() const { return ack_channel_; }

 private:
  void on_message(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void reply(const DecodedCommand& d, int64_t now_utime);
  void run();

  std::string channel_;
  std::string ack_channel_;
  CommandIntake intake_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<uint64_t> acks_sent_{0};
};

}  // namespace rigctl
