#include "tools/fault_spec.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace rigctl {

namespace {

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> parts;
  std::stringstream ss(s);
  std::string part;
  while (std::getline(ss, part, sep)) parts.push_back(part);
  if (!s.empty() && s.back() == sep) parts.emplace_back();
  return parts;
}

[[noreturn]] void bad(const std::string& spec, const std::string& why) {
  throw std::invalid_argument("fault '" + spec + "': " + why);
}

double seconds(const std::string& spec, const std::string& text, const char* what) {
  std::size_t used = 0;
  double v = 0.0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(v) || v < 0.0) {
    bad(spec, std::string(what) + " '" + text + "' is not a time in seconds >= 0");
  }
  return v;
}

int integer(const std::string& spec, const std::string& text, const char* what) {
  std::size_t used = 0;
  long v = 0;
  try {
    v = std::stol(text, &used, 0);  // accepts 0x5000
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || v < 0 || v > 0xFFFF) bad(spec, std::string(what) + " '" + text + "' is not an integer 0..65535");
  return static_cast<int>(v);
}

}  // namespace

FaultSpec parse_fault_spec(const std::string& spec) {
  const auto at = spec.find('@');
  if (at == std::string::npos) bad(spec, "expected KIND@TIME[:ARG...]");
  const std::string kind = spec.substr(0, at);
  const auto args = split(spec.substr(at + 1), ':');
  FaultSpec f;
  f.text = spec;
  f.at_s = seconds(spec, args.at(0), "time");
  const auto need = [&](std::size_t min, std::size_t max, const char* usage) {
    if (args.size() - 1 < min || args.size() - 1 > max) bad(spec, std::string("expected ") + usage);
  };
  if (kind == "silence") {
    f.kind = FaultKind::kSilence;
    need(0, 1, "silence@TIME[:DURATION]");
    if (args.size() > 1) f.duration_s = seconds(spec, args[1], "duration");
  } else if (kind == "drop") {
    f.kind = FaultKind::kDrop;
    need(0, 0, "drop@TIME");
  } else if (kind == "late") {
    f.kind = FaultKind::kLate;
    need(1, 2, "late@TIME:DELAY[:DURATION]");
    f.delay_s = seconds(spec, args[1], "delay");
    if (args.size() > 2) f.duration_s = seconds(spec, args[2], "duration");
  } else if (kind == "exception") {
    f.kind = FaultKind::kException;
    need(2, 2, "exception@TIME:CHANNEL:CODE");
    f.channel = args[1];
    f.code = integer(spec, args[2], "exception code");
    if (f.code < 1 || f.code > 0xFF) bad(spec, "exception code must be 1..255");
  } else if (kind == "stuck" || kind == "rail") {
    f.kind = kind == "stuck" ? FaultKind::kStuck : FaultKind::kRail;
    need(1, 1, "stuck@TIME:CHANNEL or rail@TIME:CHANNEL");
    f.channel = args[1];
  } else if (kind == "heartbeat") {
    f.kind = FaultKind::kHeartbeat;
    need(1, 1, "heartbeat@TIME:DURATION");
    f.duration_s = seconds(spec, args[1], "duration");
  } else if (kind == "emcy") {
    f.kind = FaultKind::kEmcy;
    need(2, 2, "emcy@TIME:CODE:ERROR_REGISTER");
    f.code = integer(spec, args[1], "EMCY code");
    f.error_register = integer(spec, args[2], "error register");
    if (f.error_register > 0xFF) bad(spec, "error register must be 0..255");
  } else {
    bad(spec, "unknown kind '" + kind + "' (silence, drop, late, exception, stuck, rail, heartbeat, emcy)");
  }
  if (f.channel.empty() && (f.kind == FaultKind::kException || f.kind == FaultKind::kStuck || f.kind == FaultKind::kRail)) {
    bad(spec, "needs a channel name");
  }
  return f;
}

}  // namespace rigctl
