// Operator command authentication: key file, HMAC tags, canonical encoding,
// a bounds-checked decoder of the LCM bytes and the replay table.
#include "rt/comms/operator_auth.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace rigctl {

namespace {

constexpr char kCommandLabel[] = "rigctl.operator_command.v1";  // sizeof includes the 0x00 that ends it
constexpr char kAckLabel[] = "rigctl.operator_ack.v1";

// --- canonical encoding -----------------------------------------------------

void put_u32(std::vector<uint8_t>& out, uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<uint8_t>(v >> s));
}
void put_u64(std::vector<uint8_t>& out, uint64_t v) {
  for (int s = 56; s >= 0; s -= 8) out.push_back(static_cast<uint8_t>(v >> s));
}
void put_string(std::vector<uint8_t>& out, const std::string& s) {
  put_u32(out, static_cast<uint32_t>(s.size()));
  out.insert(out.end(), s.begin(), s.end());
}
// A buffer that starts with the label and its terminating 0x00.
template <std::size_t N>
std::vector<uint8_t> start_with_label(const char (&label)[N], std::size_t reserve) {
  std::vector<uint8_t> out(label, label + N);
  out.reserve(N + reserve);
  return out;
}
uint64_t double_bits(double v) {
  uint64_t bits = 0;
  std::memcpy(&bits, &v, sizeof bits);
  return bits;
}

// --- LCM decoding -------------------------------------------------------------

// Reads the LCM encoding of operator_command_t by hand, every read bounds
// checked. The generated decode() (lcm-gen 1.3.1) is not used on untrusted
// bytes: it passes a string's length field minus one to std::string::assign
// unchecked, so a length of 0 throws length_error and INT32_MIN overflows.
class Reader {
 public:
  Reader(const void* data, std::size_t size) : p_(static_cast<const uint8_t*>(data)), n_(size) {}

  bool u64(uint64_t& v) {
    if (n_ - pos_ < 8) return false;
    v = 0;
    for (int i = 0; i < 8; ++i) v = (v << 8) | p_[pos_ + i];
    pos_ += 8;
    return true;
  }
  bool i64(int64_t& v) {
    uint64_t u = 0;
    if (!u64(u)) return false;
    v = static_cast<int64_t>(u);
    return true;
  }
  bool i32(int32_t& v) {
    if (n_ - pos_ < 4) return false;
    uint32_t u = 0;
    for (int i = 0; i < 4; ++i) u = (u << 8) | p_[pos_ + i];
    pos_ += 4;
    v = static_cast<int32_t>(u);
    return true;
  }
  bool f64(double& v) {
    uint64_t u = 0;
    if (!u64(u)) return false;
    std::memcpy(&v, &u, sizeof v);
    return true;
  }
  bool bytes(uint8_t* out, std::size_t count) {
    if (n_ - pos_ < count) return false;
    std::memcpy(out, p_ + pos_, count);
    pos_ += count;
    return true;
  }
  // LCM string: int32 length including a terminating NUL, the bytes, the NUL.
  // Refuses embedded NULs and anything longer than max_chars.
  bool string(std::string& out, std::size_t max_chars) {
    int32_t len = 0;
    if (!i32(len) || len < 1 || static_cast<std::size_t>(len) - 1 > max_chars) return false;
    const std::size_t count = static_cast<std::size_t>(len);
    if (n_ - pos_ < count || p_[pos_ + count - 1] != 0) return false;
    const char* s = reinterpret_cast<const char*>(p_ + pos_);
    if (std::memchr(s, 0, count - 1) != nullptr) return false;
    out.assign(s, count - 1);
    pos_ += count;
    return true;
  }
  bool at_end() const { return pos_ == n_; }

 private:
  const uint8_t* p_;
  std::size_t n_;
  std::size_t pos_ = 0;
};

std::string fmt_double(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

DecodedCommand reject(DecodedCommand d, RejectReason r, std::string detail) {
  d.reason = r;
  d.detail = std::move(detail);
  return d;
}

// Form, version, sender, sequence, tag and staleness of a decoded message:
// what a command and a claim share. False (d's reason and detail set) when
// it fails one of them.
bool check_signed(const operator_command_t& msg, const OperatorKey& key, const CommandPolicy& policy, int64_t now_utime,
                  DecodedCommand& d) {
  d.sender = msg.sender;
  d.sequence = msg.sequence;
  d.utime = msg.utime;
  // The version decides the canonical encoding, so it is checked before the tag.
  if (msg.version != kOperatorWireVersion) {
    d = reject(d, RejectReason::kBadVersion, "field 'version' = " + std::to_string(msg.version) + ", this rig speaks " + std::to_string(kOperatorWireVersion));
    return false;
  }
  if (!valid_sender_id(msg.sender)) {
    d = reject(d, RejectReason::kMalformed, "field 'sender' is not 1-64 chars of [A-Za-z0-9_.@-]");
    return false;
  }
  if (msg.sequence <= 0) {
    d = reject(d, RejectReason::kMalformed, "field 'sequence' = " + std::to_string(msg.sequence) + ", must be > 0");
    return false;
  }
  // Nothing below is looked at before the tag verifies: an unauthenticated
  // packet learns no more than "bad_tag".
  const std::vector<uint8_t> canon = canonical_bytes(msg);
  if (!tags_equal(hmac_sha256(key, canon.data(), canon.size()), msg.tag)) {
    d = reject(d, RejectReason::kBadTag, "field 'tag' does not verify (forged, corrupted or signed with another key)");
    return false;
  }
  // Difference in long double: utime - now can overflow int64 for hostile values.
  const long double age_us = static_cast<long double>(now_utime) - static_cast<long double>(msg.utime);
  if (age_us > policy.max_age_us || -age_us > policy.max_age_us) {
    d = reject(d, RejectReason::kStale,
               "field 'utime' is " + fmt_double(static_cast<double>(std::fabs(age_us)) * 1e-6) + " s " +
                   (age_us > 0 ? "behind" : "ahead of") + " the rig's clock (window " +
                   fmt_double(static_cast<double>(policy.max_age_us) * 1e-6) + " s)");
    return false;
  }
  if (msg.utime < policy.not_before_utime) {
    d = reject(d, RejectReason::kStale,
               "field 'utime' is " + fmt_double(static_cast<double>(policy.not_before_utime - msg.utime) * 1e-6) +
                   " s before this rig's command receiver started: a command from before a restart is not taken; send it again");
    return false;
  }
  return true;
}

// The command and its value, once the message is authentic and fresh.
DecodedCommand check_command(const operator_command_t& msg, const CommandPolicy& policy, DecodedCommand d) {
  OperatorCommandKind kind{};
  if (!parse_command_name(msg.command, kind)) return reject(d, RejectReason::kUnknownCommand, "field 'command' = '" + msg.command + "' is not a command");
  if (!std::isfinite(msg.value)) return reject(d, RejectReason::kBadValue, "field 'value' = " + fmt_double(msg.value) + " is not finite");
  if (kind == OperatorCommandKind::kSetpoint) {
    if (!(policy.setpoint_min <= policy.setpoint_max)) {
      return reject(d, RejectReason::kOutOfLimits, "setpoint " + fmt_double(msg.value) + ": no setpoint limits configured on this rig");
    }
    if (msg.value < policy.setpoint_min || msg.value > policy.setpoint_max) {
      const std::string unit = policy.setpoint_unit.empty() ? "" : " " + policy.setpoint_unit;
      return reject(d, RejectReason::kOutOfLimits,
                    "setpoint " + fmt_double(msg.value) + unit + " outside [" + fmt_double(policy.setpoint_min) + ", " +
                        fmt_double(policy.setpoint_max) + "]" + unit);
    }
  } else if (msg.value != 0.0) {
    return reject(d, RejectReason::kBadValue, "field 'value' = " + fmt_double(msg.value) + " for '" + msg.command + "', which takes none (must be 0)");
  }
  d.reason = RejectReason::kNone;
  d.command.kind = kind;
  d.command.value = kind == OperatorCommandKind::kSetpoint ? msg.value : 0.0;
  d.command.sequence = static_cast<uint64_t>(msg.sequence);
  return d;
}

DecodedCommand decode_unchecked(const void* data, std::size_t size, const OperatorKey& key,
                                const CommandPolicy& policy, int64_t now_utime) {
  DecodedCommand d;
  if (data == nullptr || size == 0) return reject(d, RejectReason::kMalformed, "empty message");
  Reader r(data, size);
  operator_command_t msg;
  uint64_t fingerprint = 0;
  if (!r.u64(fingerprint)) return reject(d, RejectReason::kMalformed, "message of " + std::to_string(size) + " bytes is too short");
  if (fingerprint != static_cast<uint64_t>(operator_command_t::getHash())) {
    return reject(d, RejectReason::kMalformed, "not a rigctl.operator_command_t (LCM fingerprint differs)");
  }
  if (!r.i32(msg.version)) return reject(d, RejectReason::kMalformed, "truncated before field 'version'");
  if (!r.string(msg.sender, kMaxSenderLength)) return reject(d, RejectReason::kMalformed, "field 'sender': truncated, not a string or longer than 64");
  d.sender = msg.sender;
  if (!r.i64(msg.sequence)) return reject(d, RejectReason::kMalformed, "truncated before field 'sequence'");
  d.sequence = msg.sequence;
  if (!r.i64(msg.utime)) return reject(d, RejectReason::kMalformed, "truncated before field 'utime'");
  d.utime = msg.utime;
  if (!r.string(msg.command, kMaxCommandNameLength)) return reject(d, RejectReason::kMalformed, "field 'command': truncated, not a string or longer than 32");
  if (!r.f64(msg.value)) return reject(d, RejectReason::kMalformed, "truncated before field 'value'");
  if (!r.bytes(msg.tag, kOperatorTagBytes)) return reject(d, RejectReason::kMalformed, "truncated in field 'tag'");
  if (!r.at_end()) return reject(d, RejectReason::kMalformed, "trailing bytes after field 'tag'");
  if (!check_signed(msg, key, policy, now_utime, d)) return d;
  return check_command(msg, policy, d);
}

bool decode_ack_unchecked(const void* data, std::size_t size, operator_ack_t& ack) {
  if (data == nullptr) return false;
  Reader r(data, size);
  uint64_t fingerprint = 0;
  if (!r.u64(fingerprint) || fingerprint != static_cast<uint64_t>(operator_ack_t::getHash())) return false;
  uint8_t accepted = 0;
  if (!r.i32(ack.version) || !r.i64(ack.utime) || !r.string(ack.sender, kMaxSenderLength) || !r.i64(ack.sequence) ||
      !r.bytes(&accepted, 1) || accepted > 1 || !r.string(ack.reason, 64) || !r.string(ack.message, 1024) ||
      !r.bytes(ack.tag, kOperatorTagBytes)) {
    return false;
  }
  ack.accepted = static_cast<int8_t>(accepted);
  return r.at_end();
}

}  // namespace

bool decode_operator_ack(const void* data, std::size_t size, operator_ack_t& ack) noexcept {
  try {
    return decode_ack_unchecked(data, size, ack);
  } catch (...) {
    return false;
  }
}

// --- key ----------------------------------------------------------------------

OperatorKey OperatorKey::from_bytes(const void* data, std::size_t size) {
  if (size < kOperatorKeyMinBytes) {
    throw std::invalid_argument("operator key of " + std::to_string(size) + " bytes, needs at least " + std::to_string(kOperatorKeyMinBytes));
  }
  OperatorKey k;
  const auto* p = static_cast<const uint8_t*>(data);
  k.bytes_.assign(p, p + size);
  return k;
}

OperatorKey::~OperatorKey() {
  if (!bytes_.empty()) OPENSSL_cleanse(bytes_.data(), bytes_.size());
}

namespace {

// Another user who owns the key, or may write to its folder (and so replace
// it with a key of their own), can command the rig: the mode alone does not
// say who holds the secret.
void check_key_owner(const std::string& path, const struct stat& st) {
  const std::string what = "operator key file '" + path + "': ";
  const uid_t me = ::geteuid();
  if (st.st_uid != me && st.st_uid != 0) {
    throw std::runtime_error(what + "is owned by uid " + std::to_string(st.st_uid) + ", not by this process's user (uid " +
                             std::to_string(me) + ") or root: chown it to the service's user");
  }
  const std::size_t slash = path.rfind('/');
  const std::string dir = slash == std::string::npos ? "." : slash == 0 ? "/" : path.substr(0, slash);
  struct stat ds{};
  if (::stat(dir.c_str(), &ds) != 0) throw std::runtime_error(what + "folder '" + dir + "': " + std::strerror(errno));
  // A sticky folder (like /tmp) lets nobody but a file's owner remove or
  // rename it, so its write bits give others no way to swap the key.
  const bool others_write = (ds.st_mode & (S_IWGRP | S_IWOTH)) != 0 && (ds.st_mode & S_ISVTX) == 0;
  if (others_write || (ds.st_uid != me && ds.st_uid != 0)) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(ds.st_mode & 07777));
    throw std::runtime_error(what + "is in folder '" + dir + "' (mode " + mode + ", owner uid " + std::to_string(ds.st_uid) +
                             ") where another user could replace it: keep the key in a folder only its owner (or root) may write to");
  }
}

}  // namespace

OperatorKey load_operator_key(const std::string& path) {
  const std::string what = "operator key file '" + path + "': ";
  // O_NOFOLLOW: the mode checked below must be the key's own, not a symlink's
  // target that someone could swap. fstat on the open descriptor: no race
  // between the check and the read.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) {
    const int err = errno;
    throw std::runtime_error(what + (err == ELOOP ? std::string("is a symbolic link; give the real file") : std::strerror(err)));
  }
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st{};
  if (::fstat(fd, &st) != 0) throw std::runtime_error(what + "stat: " + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) throw std::runtime_error(what + "is not a regular file");
  if ((st.st_mode & (S_IRWXG | S_IRWXO)) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
    throw std::runtime_error(what + "is accessible by group or others (mode " + mode +
                             "); a key must be readable only by its owner: chmod 600 '" + path + "'");
  }
  check_key_owner(path, st);
  if (st.st_size < static_cast<off_t>(kOperatorKeyMinBytes)) {
    throw std::runtime_error(what + "is " + std::to_string(st.st_size) + " bytes, a key needs at least " +
                             std::to_string(kOperatorKeyMinBytes) + " (head -c 32 /dev/urandom > key)");
  }
  if (st.st_size > static_cast<off_t>(kOperatorKeyMaxBytes)) {
    throw std::runtime_error(what + "is " + std::to_string(st.st_size) + " bytes, more than a key (at most " +
                             std::to_string(kOperatorKeyMaxBytes) + ")");
  }
  std::vector<uint8_t> buf(static_cast<std::size_t>(st.st_size));
  std::size_t got = 0;
  while (got < buf.size()) {
    const ssize_t n = ::read(fd, buf.data() + got, buf.size() - got);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      OPENSSL_cleanse(buf.data(), buf.size());
      throw std::runtime_error(what + "read failed: " + (n < 0 ? std::strerror(errno) : "file shrank while reading"));
    }
    got += static_cast<std::size_t>(n);
  }
  OperatorKey key = OperatorKey::from_bytes(buf.data(), buf.size());
  OPENSSL_cleanse(buf.data(), buf.size());
  return key;
}

// --- tags -----------------------------------------------------------------------

OperatorTag hmac_sha256(const OperatorKey& key, const uint8_t* data, std::size_t size) {
  OperatorTag tag{};
  unsigned int len = 0;
  static const uint8_t kEmpty = 0;
  if (HMAC(EVP_sha256(), key.data(), static_cast<int>(key.size()), size == 0 ? &kEmpty : data, size, tag.data(), &len) == nullptr ||
      len != tag.size()) {
    // Cannot happen with a working libcrypto; refuse loudly rather than
    // return a tag that means nothing (decode_operator_command turns this
    // into a rejection).
    throw std::runtime_error("HMAC-SHA256 failed in libcrypto");
  }
  return tag;
}

bool tags_equal(const OperatorTag& a, const uint8_t* b) { return CRYPTO_memcmp(a.data(), b, a.size()) == 0; }

bool tag_from_hex(std::string_view hex, uint8_t* out) {
  if (hex.size() != 2 * kOperatorTagBytes) return false;
  const std::string text(hex);  // libcrypto wants a terminated string
  std::size_t n = 0;
  // Separator '\0': plain digit pairs only (no "ab:cd").
  return OPENSSL_hexstr2buf_ex(out, kOperatorTagBytes, &n, text.c_str(), '\0') == 1 && n == kOperatorTagBytes;
}

std::vector<uint8_t> canonical_bytes(const operator_command_t& msg) {
  std::vector<uint8_t> out = start_with_label(kCommandLabel, 4 + 4 + msg.sender.size() + 8 + 8 + 4 + msg.command.size() + 8);
  put_u32(out, static_cast<uint32_t>(msg.version));
  put_string(out, msg.sender);
  put_u64(out, static_cast<uint64_t>(msg.sequence));
  put_u64(out, static_cast<uint64_t>(msg.utime));
  put_string(out, msg.command);
  put_u64(out, double_bits(msg.value));
  return out;
}

std::vector<uint8_t> canonical_bytes(const operator_ack_t& msg) {
  std::vector<uint8_t> out =
      start_with_label(kAckLabel, 4 + 8 + 4 + msg.sender.size() + 8 + 1 + 4 + msg.reason.size() + 4 + msg.message.size());
  put_u32(out, static_cast<uint32_t>(msg.version));
  put_u64(out, static_cast<uint64_t>(msg.utime));
  put_string(out, msg.sender);
  put_u64(out, static_cast<uint64_t>(msg.sequence));
  out.push_back(msg.accepted ? 1 : 0);
  put_string(out, msg.reason);
  put_string(out, msg.message);
  return out;
}

void sign(operator_command_t& msg, const OperatorKey& key) {
  const auto canon = canonical_bytes(msg);
  const OperatorTag tag = hmac_sha256(key, canon.data(), canon.size());
  std::memcpy(msg.tag, tag.data(), tag.size());
}

void sign(operator_ack_t& msg, const OperatorKey& key) {
  const auto canon = canonical_bytes(msg);
  const OperatorTag tag = hmac_sha256(key, canon.data(), canon.size());
  std::memcpy(msg.tag, tag.data(), tag.size());
}

bool tag_valid(const operator_ack_t& msg, const OperatorKey& key) {
  const auto canon = canonical_bytes(msg);
  return tags_equal(hmac_sha256(key, canon.data(), canon.size()), msg.tag);
}

template <typename Msg>
static std::vector<uint8_t> encode_any(const Msg& msg) {
  const int size = msg.getEncodedSize();
  std::vector<uint8_t> buf(static_cast<std::size_t>(size));
  if (msg.encode(buf.data(), 0, size) != size) throw std::runtime_error("LCM encoding of an operator message failed");
  return buf;
}
std::vector<uint8_t> lcm_encode(const operator_command_t& msg) { return encode_any(msg); }
std::vector<uint8_t> lcm_encode(const operator_ack_t& msg) { return encode_any(msg); }

// --- names ----------------------------------------------------------------------

bool parse_command_name(std::string_view name, OperatorCommandKind& kind) {
  for (auto k : {OperatorCommandKind::kHydraulicsOff, OperatorCommandKind::kHydraulicsLow, OperatorCommandKind::kHydraulicsHigh,
                 OperatorCommandKind::kArm, OperatorCommandKind::kStart, OperatorCommandKind::kHold,
                 OperatorCommandKind::kResume, OperatorCommandKind::kStop, OperatorCommandKind::kReset,
                 OperatorCommandKind::kSetpoint, OperatorCommandKind::kStopAtBlockEnd}) {
    if (to_string(k) == name) {
      kind = k;
      return true;
    }
  }
  return false;
}

bool valid_sender_id(std::string_view sender) {
  if (sender.empty() || sender.size() > kMaxSenderLength) return false;
  for (char c : sender) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
                    c == '.' || c == '@' || c == '-';
    if (!ok) return false;
  }
  return sender != "." && sender != "..";  // it names a state file
}

std::string_view to_string(RejectReason r) {
  switch (r) {
    case RejectReason::kNone: return "accepted";
    case RejectReason::kMalformed: return "malformed";
    case RejectReason::kBadVersion: return "bad_version";
    case RejectReason::kBadTag: return "bad_tag";
    case RejectReason::kStale: return "stale";
    case RejectReason::kReplayed: return "replayed";
    case RejectReason::kUnknownCommand: return "unknown_command";
    case RejectReason::kBadValue: return "bad_value";
    case RejectReason::kOutOfLimits: return "out_of_limits";
    case RejectReason::kTooManySenders: return "too_many_senders";
    case RejectReason::kQueueFull: return "queue_full";
    case RejectReason::kNotInControl: return "not_in_control";
    case RejectReason::kControlHeld: return "control_held";
    case RejectReason::kCount: break;
  }
  return "unknown";
}

// --- decoding and verification ---------------------------------------------------

DecodedCommand decode_operator_command(const void* data, std::size_t size, const OperatorKey& key,
                                       const CommandPolicy& policy, int64_t now_utime) noexcept {
  // Total: the only things that can throw inside are allocation (bounded by
  // the 64/32-character string limits) and libcrypto failing; either is a
  // rejection, never an exception out of here.
  try {
    return decode_unchecked(data, size, key, policy, now_utime);
  } catch (...) {
    DecodedCommand d;
    d.reason = RejectReason::kMalformed;
    return d;
  }
}

uint64_t RejectCounters::rejected() const noexcept {
  uint64_t n = 0;
  for (std::size_t i = 1; i < kRejectReasonCount; ++i) n += counts_[i].load(std::memory_order_relaxed);
  return n;
}

OperatorVerifier::OperatorVerifier(OperatorKey key, CommandPolicy policy, std::size_t max_senders)
    : key_(std::move(key)), policy_(std::move(policy)), max_senders_(max_senders < 1 ? 1 : max_senders) {
  if (!(policy_.max_age_us > 0)) throw std::invalid_argument("operator commands: max_age_us must be > 0");
  senders_.reserve(max_senders_);
}

bool OperatorVerifier::make_room(int64_t now_utime) {
  if (senders_.size() < max_senders_) return true;
  const long double horizon = 2.0L * static_cast<long double>(policy_.max_age_us);
  for (auto it = senders_.begin(); it != senders_.end();) {
    const long double idle = static_cast<long double>(now_utime) - static_cast<long double>(it->second.last_accept_utime);
    it = idle > horizon ? senders_.erase(it) : std::next(it);
  }
  return senders_.size() < max_senders_;
}

void OperatorVerifier::check_replay(DecodedCommand& d, int64_t now_utime) {
  // Only authentic, fresh, valid messages reach the replay table: a forged
  // packet cannot push a sender's sequence up and lock its real commands out.
  auto it = senders_.find(d.sender);
  if (it != senders_.end() && d.sequence <= it->second.last_sequence) {
    d.reason = RejectReason::kReplayed;
    d.detail = "field 'sequence' = " + std::to_string(d.sequence) + " is not above " +
               std::to_string(it->second.last_sequence) + ", the last accepted from '" + d.sender + "'";
  } else if (it == senders_.end() && !make_room(now_utime)) {
    d.reason = RejectReason::kTooManySenders;
    d.detail = "replay table full (" + std::to_string(max_senders_) + " senders active in the last " +
               fmt_double(2e-6 * static_cast<double>(policy_.max_age_us)) + " s)";
  } else {
    SenderState& s = senders_[d.sender];
    s.last_sequence = d.sequence;
    s.last_accept_utime = now_utime;
  }
}

DecodedCommand OperatorVerifier::verify(const void* data, std::size_t size, int64_t now_utime) {
  DecodedCommand d = decode_operator_command(data, size, key_, policy_, now_utime);
  if (d.ok()) check_replay(d, now_utime);
  counters_.add(d.reason);
  return d;
}

DecodedCommand OperatorVerifier::verify_claim(const operator_command_t& msg, std::string_view name, int64_t now_utime) {
  DecodedCommand d;
  try {
    if (msg.command != name || msg.value != 0.0) {
      d = reject(d, RejectReason::kMalformed, "a claim is the command '" + std::string(name) + "' with value 0");
    } else if (check_signed(msg, key_, policy_, now_utime, d)) {
      d.reason = RejectReason::kNone;
      check_replay(d, now_utime);
    }
  } catch (...) {  // libcrypto failing or no memory: a refusal, never an exception out of here
    d = reject(d, RejectReason::kMalformed, "the claim could not be checked");
  }
  if (!d.ok()) counters_.add(d.reason);
  return d;
}

}  // namespace rigctl
