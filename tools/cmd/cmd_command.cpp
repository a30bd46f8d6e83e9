// `rigctl cmd`: one signed operator command out, one verified ack back.
#include "tools/cmd/cmd_command.hpp"
#include "rt/wall_clock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include <lcm/lcm-cpp.hpp>

#include "rt/comms/operator_auth.hpp"

namespace rigctl {

namespace {

// USER@HOSTNAME with anything outside the sender alphabet replaced by '_'.
std::string default_sender() {
  const char* user = std::getenv("USER");
  char host[256] = {};
  if (::gethostname(host, sizeof host - 1) != 0) std::strcpy(host, "host");
  std::string s = std::string(user != nullptr && *user != '\0' ? user : "uid" + std::to_string(::getuid())) + "@" + host;
  for (char& c : s) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '.' ||
                    c == '@' || c == '-';
    if (!ok) c = '_';
  }
  if (s.size() > kMaxSenderLength) s.resize(kMaxSenderLength);
  return s;
}

// Listens on the ack channel for the reply to (sender, sequence).
struct AckWaiter {
  const OperatorKey* key;
  std::string sender;
  int64_t sequence;
  bool got = false;
  operator_ack_t ack;
  int bad_tags = 0;  // replies to us whose tag did not verify: someone else's key, or forged

  void on_message(const lcm::ReceiveBuffer* rbuf, const std::string& /*channel*/) {
    operator_ack_t a;
    if (got || !decode_operator_ack(rbuf->data, rbuf->data_size, a)) return;
    if (a.sender != sender || a.sequence != sequence) return;  // someone else's reply
    if (a.version != kOperatorWireVersion || !tag_valid(a, *key)) {
      ++bad_tags;
      return;
    }
    ack = a;
    got = true;
  }
};

std::string regex_literal(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_')) out += '\\';
    out += c;
  }
  return out;
}

std::string format_seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", s);
  return buf;
}

}  // namespace

std::string default_sequence_state_path(const std::string& sender) {
  namespace fs = std::filesystem;
  const char* xdg = std::getenv("XDG_STATE_HOME");
  const char* home = std::getenv("HOME");
  fs::path dir;
  if (xdg != nullptr && *xdg == '/') {
    dir = fs::path(xdg) / "rigctl";
  } else if (home != nullptr && *home != '\0') {
    dir = fs::path(home) / ".local" / "state" / "rigctl";
  } else {
    throw std::runtime_error("neither XDG_STATE_HOME nor HOME is set: give the sequence state file with --state-file");
  }
  return (dir / (sender + ".seq")).string();
}

int64_t reserve_sequence(const std::string& state_path, int64_t now_utime) {
  namespace fs = std::filesystem;
  const std::string what = "sequence state file '" + state_path + "': ";
  const fs::path parent = fs::path(state_path).parent_path();
  if (!parent.empty()) {
    std::error_code ec;
    fs::create_directories(parent, ec);
    if (ec) throw std::runtime_error(what + "cannot create its folder: " + ec.message());
  }
  const int fd = ::open(state_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0600);
  if (fd < 0) throw std::runtime_error(what + std::strerror(errno));
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }  // also releases the lock
  } closer{fd};
  // Two `rigctl cmd` at once from one sender must not take the same number.
  if (::flock(fd, LOCK_EX) != 0) throw std::runtime_error(what + "flock: " + std::strerror(errno));

  char buf[64] = {};
  const ssize_t n = ::pread(fd, buf, sizeof buf - 1, 0);
  if (n < 0) throw std::runtime_error(what + "read: " + std::strerror(errno));
  int64_t last = 0;
  std::string text(buf, static_cast<std::size_t>(n));
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  if (!text.empty()) {
    char* end = nullptr;
    errno = 0;
    const long long v = std::strtoll(text.c_str(), &end, 10);
    if (errno != 0 || end == text.c_str() || *end != '\0' || v < 0) {
      throw std::runtime_error(what + "does not hold a sequence number ('" + text + "'); remove it to start again from the clock");
    }
    last = v;
  }
  if (last == std::numeric_limits<int64_t>::max()) throw std::runtime_error(what + "sequence exhausted");
  const int64_t next = std::max(last + 1, now_utime);
  const std::string out = std::to_string(next) + "\n";
  if (::ftruncate(fd, 0) != 0 || ::pwrite(fd, out.data(), out.size(), 0) != static_cast<ssize_t>(out.size()) ||
      ::fsync(fd) != 0) {
    throw std::runtime_error(what + "write: " + std::strerror(errno));
  }
  return next;
}

namespace {

// The command as the wire carries it, from the command line.
struct CommandToSend {
  std::string name;  // the wire's name: the CLI's hyphens as underscores
  OperatorCommandKind kind{};
  double value = 0.0;
  std::string sender;
};

// Checks the command line; on a usage error writes why on `err` and returns false.
bool read_command(const CmdOptions& o, CommandToSend& c, std::ostream& err) {
  c.name = o.command;
  std::replace(c.name.begin(), c.name.end(), '-', '_');
  if (!parse_command_name(c.name, c.kind)) {
    err << "rigctl cmd: unknown command '" << o.command
        << "' (arm start hold resume stop reset hydraulics-low hydraulics-high hydraulics-off setpoint VALUE stop-at-block-end)\n";
    return false;
  }
  if (c.kind == OperatorCommandKind::kSetpoint) {
    char* end = nullptr;
    c.value = o.value.empty() ? std::nan("") : std::strtod(o.value.c_str(), &end);
    if (o.value.empty() || end == nullptr || *end != '\0' || !std::isfinite(c.value)) {
      err << "rigctl cmd: setpoint needs a finite number VALUE (SI units), got '" << o.value << "'\n";
      return false;
    }
  } else if (!o.value.empty()) {
    err << "rigctl cmd: '" << o.command << "' takes no value (got '" << o.value << "')\n";
    return false;
  }
  if (o.key_path.empty()) {
    err << "rigctl cmd: --key FILE is required\n";
    return false;
  }
  if (!(o.wait_ack_s >= 0.0) || o.wait_ack_s > 3600.0) {
    err << "rigctl cmd: --wait-ack must be 0..3600 s\n";
    return false;
  }
  c.sender = o.sender.empty() ? default_sender() : o.sender;
  if (!valid_sender_id(c.sender)) {
    err << "rigctl cmd: --sender '" << c.sender << "' must be 1-64 characters of [A-Za-z0-9_.@-]\n";
    return false;
  }
  return true;
}

// The signed message with the sender's next sequence number (reserved in its state file).
operator_command_t signed_message(const CmdOptions& o, const CommandToSend& c, const OperatorKey& key) {
  operator_command_t msg;
  msg.version = kOperatorWireVersion;
  msg.sender = c.sender;
  msg.command = c.name;
  msg.value = c.value;
  msg.utime = wall_utime_now();
  msg.sequence = reserve_sequence(o.state_path.empty() ? default_sequence_state_path(c.sender) : o.state_path, msg.utime);
  sign(msg, key);
  return msg;
}

// Handles LCM until the waiter has its acknowledgement or wait_s has passed.
void wait_for_ack(lcm::LCM& lcm, const AckWaiter& waiter, double wait_s, const std::string& ack_channel) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(wait_s);
  while (!waiter.got) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) break;
    if (lcm.handleTimeout(static_cast<int>(std::min<int64_t>(left.count(), 100))) < 0) {
      throw std::runtime_error("receiving on " + ack_channel + " failed");
    }
  }
}

// What the rig replied (or that it did not), and the exit code saying so.
int report_reply(const CmdOptions& o, const AckWaiter& waiter, const std::string& what, const std::string& ack_channel,
                 std::ostream& out) {
  if (!waiter.got) {
    out << "rigctl cmd: " << what << " sent on " << o.channel << ", no acknowledgement on " << ack_channel
        << " within " << format_seconds(o.wait_ack_s) << " s"
        << (waiter.bad_tags > 0 ? " (" + std::to_string(waiter.bad_tags) +
                                      " reply with a tag that does not verify: the rig has a different key?)"
                                : " (is the rig running, on this LCM URL and channel?)")
        << "\n";
    return kCmdNoAck;
  }
  if (waiter.ack.accepted) {
    out << "rigctl cmd: " << what << " accepted by the rig\n";
    return kCmdAccepted;
  }
  out << "rigctl cmd: " << what << " rejected by the rig: " << waiter.ack.reason << ": " << waiter.ack.message << "\n";
  return kCmdRejected;
}

}  // namespace

int run_cmd_command(const CmdOptions& o, std::ostream& out, std::ostream& err) {
  CommandToSend c;
  if (!read_command(o, c, err)) return kCmdUsage;
  const std::string ack_channel = o.ack_channel.empty() ? o.channel + "_ACK" : o.ack_channel;

  try {
    const OperatorKey key = load_operator_key(o.key_path);
    // Empty would make LCM pick its default multicast group silently.
    if (o.lcm_url.empty()) throw std::runtime_error("--lcm-url is empty");
    lcm::LCM lcm(o.lcm_url);
    if (!lcm.good()) throw std::runtime_error("cannot open LCM URL '" + o.lcm_url + "'");

    const operator_command_t msg = signed_message(o, c, key);
    const auto bytes = lcm_encode(msg);
    AckWaiter waiter{&key, c.sender, msg.sequence, false, {}, 0};
    // Subscribed before sending, so a fast reply is not missed.
    if (o.wait_ack_s > 0.0) lcm.subscribe(regex_literal(ack_channel), &AckWaiter::on_message, &waiter);
    if (lcm.publish(o.channel, bytes.data(), static_cast<unsigned int>(bytes.size())) != 0) {
      throw std::runtime_error("publishing on " + o.channel + " failed");
    }
    const std::string what = "'" + o.command + (c.kind == OperatorCommandKind::kSetpoint ? " " + o.value : "") +
                             "' (sender " + c.sender + ", sequence " + std::to_string(msg.sequence) + ")";
    if (o.wait_ack_s == 0.0) {
      out << "rigctl cmd: " << what << " sent on " << o.channel << ", not waiting for an acknowledgement\n";
      return kCmdAccepted;
    }
    wait_for_ack(lcm, waiter, o.wait_ack_s, ack_channel);
    return report_reply(o, waiter, what, ack_channel, out);
  } catch (const std::exception& e) {
    err << "rigctl cmd: " << e.what() << "\n";
    return kCmdError;
  }
}

}  // namespace rigctl
