// Where every operator command enters the rig, whichever way it came (LCM
// from `rigctl cmd`, the browser console): the one verifier with its replay
// table, the queue the loop reads, the counters per reason and the
// rate-limited log of refusals. The command receiver (LCM) and the console's
// gateway (foxglove/console) both hand their messages here, so there is one
// path into the state machine and one set of counters.
//
// No I/O of its own: refusals go to the `on_refusal` callback (the run writes
// them to its event log and the program's log). Any thread: a mutex
// serialises the producers; the loop's side of the queue stays lock-free.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <string_view>

#include "rt/comms/operator_auth.hpp"
#include "rt/comms/rate_limit.hpp"
#include "rt/safety/operator_command.hpp"
#include "rt/spsc_queue.hpp"

namespace rigctl {

// One logged refusal (or a summary: reason "suppressed", sequence 0).
struct RejectionNote {
  int64_t utime = 0;     // the rig's wall clock when it arrived
  std::string reason;    // to_string(RejectReason), e.g. "bad_tag"
  int64_t sequence = 0;  // as received
  std::string text;      // the log line's text: reason, field at fault, sender
};

// Called once a message verified, before it is queued (or a claim granted),
// under the intake's mutex: the console lets through only its holder's
// commands, and stop and hold from anyone. Returns false to refuse, with
// d.reason and d.detail set to why.
using Admission = std::function<bool(DecodedCommand& d)>;

struct CommandIntakeOptions {
  CommandPolicy policy;  // staleness window, setpoint limits, not-before time
  std::size_t queue_capacity = 64;
  std::size_t max_senders = 256;
  int refusal_logs_per_second = 20;  // more in one second are summarised (a flood must not fill the disk)
  // Called under the intake's mutex; must not throw. on_refusal: each
  // refusal line it logs (and each summary of those it did not);
  // on_accepted: each command queued for the loop.
  std::function<void(const RejectionNote&)> on_refusal;
  std::function<void(const DecodedCommand&)> on_accepted;
};

class CommandIntake {
 public:
  CommandIntake(OperatorKey key, CommandIntakeOptions options);

  // The LCM bytes of an operator_command_t: verified, admitted, queued for
  // the loop. The answer says what became of it.
  DecodedCommand submit(const void* data, std::size_t size, int64_t now_utime, const Admission& admit = {});
  // A signed claim (OperatorVerifier::verify_claim) named `name`, then admitted.
  DecodedCommand claim(const operator_command_t& msg, std::string_view name, int64_t now_utime, const Admission& admit);
  // A message refused before it could be verified (the console's unreadable
  // JSON): counted and logged as the verifier's refusals.
  void refuse(const DecodedCommand& d, int64_t now_utime);

  // Consumer side for the loop (single consumer).
  SpscQueue<OperatorCommand>& queue() { return queue_; }
  const RejectCounters& counters() const { return verifier_.counters(); }
  const OperatorKey& key() const { return verifier_.key(); }
  const CommandPolicy& policy() const { return verifier_.policy(); }

 private:
  void admit_or_refuse(DecodedCommand& d, const Admission& admit, bool counted_as_accepted);
  void log_refusal(const DecodedCommand& d, int64_t now_utime);

  std::mutex mu_;  // the verifier, the queue's producer side, the rate limit
  OperatorVerifier verifier_;
  SpscQueue<OperatorCommand> queue_;
  LogRateLimit log_limit_;
  std::function<void(const RejectionNote&)> on_refusal_;
  std::function<void(const DecodedCommand&)> on_accepted_;
};

}  // namespace rigctl
