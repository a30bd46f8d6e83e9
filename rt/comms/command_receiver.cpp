// Operator command receiver thread: LCM in, verified commands to the loop's
// queue, acks out, rejections logged.
#include "rt/comms/command_receiver.hpp"
#include "rt/wall_clock.hpp"

#include <chrono>
#include <stdexcept>

#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

namespace rigctl {

namespace {

// LCM treats a subscription's channel as a regular expression: match the
// configured name literally.
std::string regex_literal(const std::string& s) {
  std::string out;
  for (char c : s) {
    const bool plain = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
    if (!plain) out += '\\';
    out += c;
  }
  return out;
}

}  // namespace

std::string default_command_channel(const std::string& channel_prefix) { return channel_prefix + "OPERATOR"; }
std::string default_ack_channel(const std::string& command_channel) { return command_channel + "_ACK"; }

CommandReceiver::CommandReceiver(const CommandReceiverOptions& options)
    : channel_(options.channel),
      ack_channel_(options.ack_channel.empty() ? default_ack_channel(options.channel) : options.ack_channel),
      logs_per_second_(options.rejection_logs_per_second),
      on_rejection_logged_(options.on_rejection_logged),
      verifier_(load_operator_key(options.key_path), options.policy, options.max_senders),
      queue_(options.queue_capacity) {
  if (channel_.empty()) throw std::runtime_error("operator commands: empty command channel name");
  if (channel_ == ack_channel_) throw std::runtime_error("operator commands: command and ack channel are both '" + channel_ + "'");
  // An empty URL would make LCM fall back to its default multicast group.
  if (options.lcm_url.empty()) throw std::runtime_error("operator commands: no LCM URL given (e.g. udpm://...)");
  lcm_ = std::make_unique<lcm::LCM>(options.lcm_url);
  if (!lcm_->good()) throw std::runtime_error("operator commands: cannot open LCM URL '" + options.lcm_url + "'");
  // Subscribing here, not in the thread, so that the sockets are made in the
  // constructing thread's network namespace (tests rely on that).
  auto* sub = lcm_->subscribe(regex_literal(channel_), &CommandReceiver::on_message, this);
  if (sub == nullptr) throw std::runtime_error("operator commands: cannot subscribe to '" + channel_ + "'");
  // A burst from several operators must not be dropped in LCM's own queue
  // before it is counted.
  sub->setQueueCapacity(256);
}

CommandReceiver::~CommandReceiver() { stop(); }

void CommandReceiver::start() {
  if (thread_.joinable()) return;
  stop_.store(false);
  thread_ = std::thread([this] { run(); });
}

void CommandReceiver::stop() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
}

void CommandReceiver::run() {
  spdlog::info("operator commands: listening on {} (acks on {})", channel_, ack_channel_);
  while (!stop_.load(std::memory_order_relaxed)) {
    // 100 ms: how long stop() may wait.
    if (lcm_->handleTimeout(100) < 0) {
      spdlog::warn("operator commands: LCM receive failed; retrying");
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
}

void CommandReceiver::on_message(const lcm::ReceiveBuffer* rbuf, const std::string& /*channel*/) {
  const int64_t now = wall_utime_now();
  const DecodedCommand d = accept(rbuf->data, rbuf->data_size, now);
  // Nothing to address a reply to when the message did not decode as far as
  // its sender id.
  if (!d.sender.empty() && valid_sender_id(d.sender)) reply(d, now);
}

DecodedCommand CommandReceiver::submit(const void* data, std::size_t size) { return accept(data, size, wall_utime_now()); }

DecodedCommand CommandReceiver::accept(const void* data, std::size_t size, int64_t now) {
  std::lock_guard<std::mutex> lock(producer_mu_);
  DecodedCommand d = verifier_.verify(data, size, now);
  if (d.ok()) {
    if (queue_.try_push(d.command)) {
      spdlog::info("operator command '{}'{} from '{}' (sequence {}) accepted", to_string(d.command.kind),
                   d.command.kind == OperatorCommandKind::kSetpoint ? fmt::format(" {:g}", d.command.value) : std::string(),
                   d.sender, d.sequence);
    } else {
      // The sequence is used up: the sender must send again with a new one.
      verifier_.reclassify_accepted(RejectReason::kQueueFull);
      d.reason = RejectReason::kQueueFull;
      d.detail = "the loop has not taken the last " + std::to_string(queue_.capacity()) + " commands; send again";
    }
  }
  if (!d.ok()) log_rejection(d, now);
  return d;
}

void CommandReceiver::reply(const DecodedCommand& d, int64_t now_utime) {
  operator_ack_t ack;
  ack.version = kOperatorWireVersion;
  ack.utime = now_utime;
  ack.sender = d.sender;
  ack.sequence = d.sequence;
  ack.accepted = d.ok();
  ack.reason = std::string(to_string(d.reason));
  ack.message = d.ok() ? "queued for the loop" : d.detail;
  try {
    sign(ack, verifier_.key());
    const auto bytes = lcm_encode(ack);
    if (lcm_->publish(ack_channel_, bytes.data(), static_cast<unsigned int>(bytes.size())) == 0) {
      acks_sent_.fetch_add(1, std::memory_order_relaxed);
    } else {
      spdlog::warn("operator commands: publishing the ack on {} failed", ack_channel_);
    }
  } catch (const std::exception& e) {
    spdlog::warn("operator commands: ack for sequence {} from '{}' not sent: {}", d.sequence, d.sender, e.what());
  }
}

void CommandReceiver::log_rejection(const DecodedCommand& d, int64_t now_utime) {
  // Up to logs_per_second_ lines a second, then one line with the count of
  // the rest: every rejection is counted, but a flood of forged packets must
  // not fill the disk with log lines.
  if (now_utime - log_window_start_ >= 1'000'000) {
    if (suppressed_ > 0) {
      const std::string text = fmt::format("{} more rejections not logged individually (see the counters)", suppressed_);
      spdlog::warn("operator commands: {}", text);
      if (on_rejection_logged_) on_rejection_logged_(RejectionNote{now_utime, "suppressed", 0, text});
    }
    log_window_start_ = now_utime;
    logged_in_window_ = 0;
    suppressed_ = 0;
  }
  if (logged_in_window_ >= logs_per_second_) {
    ++suppressed_;
    return;
  }
  ++logged_in_window_;
  // The sender id is shown only once validated: it comes from the network.
  const std::string text = fmt::format("operator command rejected ({}): {} [sender '{}', sequence {}]", to_string(d.reason),
                                       d.detail, valid_sender_id(d.sender) ? d.sender : std::string("?"), d.sequence);
  spdlog::warn("{}", text);
  if (on_rejection_logged_) on_rejection_logged_(RejectionNote{now_utime, std::string(to_string(d.reason)), d.sequence, text});
}

}  // namespace rigctl
