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

CommandIntakeOptions intake_options(const CommandReceiverOptions& o) {
  CommandIntakeOptions i;
  i.policy = o.policy;
  // Nothing signed before this receiver started is taken: no replay across a
  // restart (rt/comms/operator_auth.hpp says why this rather than a
  // persisted replay table).
  if (i.policy.not_before_utime == 0) i.policy.not_before_utime = wall_utime_now();
  i.queue_capacity = o.queue_capacity;
  i.max_senders = o.max_senders;
  i.refusal_logs_per_second = o.rejection_logs_per_second;
  i.on_refusal = [forward = o.on_rejection_logged](const RejectionNote& n) {
    spdlog::warn("operator commands: {}", n.text);
    if (forward) forward(n);
  };
  i.on_accepted = [](const DecodedCommand& d) {
    spdlog::info("operator command '{}'{} from '{}' (sequence {}) accepted", to_string(d.command.kind),
                 d.command.kind == OperatorCommandKind::kSetpoint ? fmt::format(" {:g}", d.command.value) : std::string(),
                 d.sender, d.sequence);
  };
  return i;
}

}  // namespace

std::string default_command_channel(const std::string& channel_prefix) { return channel_prefix + "OPERATOR"; }
std::string default_ack_channel(const std::string& command_channel) { return command_channel + "_ACK"; }

CommandReceiver::CommandReceiver(const CommandReceiverOptions& options)
    : channel_(options.channel),
      ack_channel_(options.ack_channel.empty() ? default_ack_channel(options.channel) : options.ack_channel),
      intake_(load_operator_key(options.key_path), intake_options(options)) {
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
  const DecodedCommand d = intake_.submit(rbuf->data, rbuf->data_size, now);
  // Nothing to address a reply to when the message did not decode as far as
  // its sender id.
  if (!d.sender.empty() && valid_sender_id(d.sender)) reply(d, now);
}

DecodedCommand CommandReceiver::submit(const void* data, std::size_t size) {
  return intake_.submit(data, size, wall_utime_now());
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
    sign(ack, intake_.key());
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

}  // namespace rigctl
