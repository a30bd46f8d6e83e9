#include "rt/comms/command_intake.hpp"

namespace rigctl {

CommandIntake::CommandIntake(OperatorKey key, CommandIntakeOptions o)
    : verifier_(std::move(key), std::move(o.policy), o.max_senders),
      queue_(o.queue_capacity),
      log_limit_(o.refusal_logs_per_second),
      on_refusal_(std::move(o.on_refusal)),
      on_accepted_(std::move(o.on_accepted)) {}

void CommandIntake::admit_or_refuse(DecodedCommand& d, const Admission& admit, bool counted_as_accepted) {
  if (!d.ok() || !admit || admit(d)) return;
  if (d.ok()) {  // an admission that refused without saying why
    d.reason = RejectReason::kNotInControl;
    d.detail = "refused by the console";
  }
  verifier_.count_refusal(d.reason, counted_as_accepted);
}

DecodedCommand CommandIntake::submit(const void* data, std::size_t size, int64_t now_utime, const Admission& admit) {
  std::lock_guard<std::mutex> lock(mu_);
  DecodedCommand d = verifier_.verify(data, size, now_utime);
  admit_or_refuse(d, admit, true);
  if (d.ok() && !queue_.try_push(d.command)) {
    // The sequence is used up: the sender must send again with a new one.
    verifier_.count_refusal(RejectReason::kQueueFull, true);
    d.reason = RejectReason::kQueueFull;
    d.detail = "the loop has not taken the last " + std::to_string(queue_.capacity()) + " commands; send again";
  }
  if (!d.ok()) log_refusal(d, now_utime);
  else if (on_accepted_) on_accepted_(d);
  return d;
}

DecodedCommand CommandIntake::claim(const operator_command_t& msg, std::string_view name, int64_t now_utime,
                                    const Admission& admit) {
  std::lock_guard<std::mutex> lock(mu_);
  DecodedCommand d = verifier_.verify_claim(msg, name, now_utime);
  admit_or_refuse(d, admit, false);  // an accepted claim is not counted
  if (!d.ok()) log_refusal(d, now_utime);
  return d;
}

void CommandIntake::refuse(const DecodedCommand& d, int64_t now_utime) {
  std::lock_guard<std::mutex> lock(mu_);
  verifier_.count_refusal(d.reason, false);
  log_refusal(d, now_utime);
}

void CommandIntake::log_refusal(const DecodedCommand& d, int64_t now_utime) {
  if (!on_refusal_) return;
  uint64_t suppressed = 0;
  const bool write = log_limit_.admit(now_utime, &suppressed);
  if (suppressed > 0) {
    on_refusal_(RejectionNote{now_utime, "suppressed", 0,
                              std::to_string(suppressed) + " more rejections not logged individually (see the counters)"});
  }
  if (!write) return;
  // The sender id is shown only once validated: it comes from the network.
  const std::string sender = valid_sender_id(d.sender) ? d.sender : std::string("?");
  on_refusal_(RejectionNote{now_utime, std::string(to_string(d.reason)), d.sequence,
                            "operator command rejected (" + std::string(to_string(d.reason)) + "): " + d.detail +
                                " [sender '" + sender + "', sequence " + std::to_string(d.sequence) + "]"});
}

}  // namespace rigctl
