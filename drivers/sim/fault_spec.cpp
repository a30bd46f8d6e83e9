#include "drivers/sim/fault_spec.hpp"

#include "rt/parse_number.hpp"

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
  const auto v = parse_finite(text);
  if (!v || *v < 0.0) bad(spec, std::string(what) + " '" + text + "' is not a time in seconds >= 0");
  return *v;
}

double number(const std::string& spec, const std::string& text, const char* what, double min) {
  const auto v = parse_finite(text);
  if (!v || *v < min) {
    bad(spec, std::string(what) + " '" + text + "' is not a finite number" + (min == 0.0 ? " >= 0" : ""));
  }
  return *v;
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

// A fault's arguments after KIND@: the time, then ARG... .
struct FaultArgs {
  const std::string& spec;
  std::vector<std::string> args;
  // The count of ARGs after the time, else the usage.
  void need(std::size_t min, std::size_t max, const char* usage) const {
    if (args.size() - 1 < min || args.size() - 1 > max) bad(spec, std::string("expected ") + usage);
  }
};

// The faults on the wire (rig-sim's Modbus DAQ and CANopen valve; stuck and
// rail in the process too); false: not one of them.
bool read_wire_fault(const std::string& kind, const FaultArgs& a, FaultSpec& f) {
  if (kind == "silence") {
    f.kind = FaultKind::kSilence;
    a.need(0, 1, "silence@TIME[:DURATION]");
    if (a.args.size() > 1) f.duration_s = seconds(a.spec, a.args[1], "duration");
  } else if (kind == "drop") {
    f.kind = FaultKind::kDrop;
    a.need(0, 0, "drop@TIME");
  } else if (kind == "late") {
    f.kind = FaultKind::kLate;
    a.need(1, 2, "late@TIME:DELAY[:DURATION]");
    f.delay_s = seconds(a.spec, a.args[1], "delay");
    if (a.args.size() > 2) f.duration_s = seconds(a.spec, a.args[2], "duration");
  } else if (kind == "exception") {
    f.kind = FaultKind::kException;
    a.need(2, 2, "exception@TIME:CHANNEL:CODE");
    f.channel = a.args[1];
    f.code = integer(a.spec, a.args[2], "exception code");
    if (f.code < 1 || f.code > 0xFF) bad(a.spec, "exception code must be 1..255");
  } else if (kind == "stuck" || kind == "rail") {
    f.kind = kind == "stuck" ? FaultKind::kStuck : FaultKind::kRail;
    a.need(1, 1, "stuck@TIME:CHANNEL or rail@TIME:CHANNEL");
    f.channel = a.args[1];
  } else if (kind == "heartbeat") {
    f.kind = FaultKind::kHeartbeat;
    a.need(1, 1, "heartbeat@TIME:DURATION");
    f.duration_s = seconds(a.spec, a.args[1], "duration");
  } else if (kind == "hold") {
    f.kind = FaultKind::kHold;
    a.need(1, 1, "hold@TIME:DURATION");
    f.duration_s = seconds(a.spec, a.args[1], "duration");
  } else if (kind == "emcy") {
    f.kind = FaultKind::kEmcy;
    a.need(2, 2, "emcy@TIME:CODE:ERROR_REGISTER");
    f.code = integer(a.spec, a.args[1], "EMCY code");
    f.error_register = integer(a.spec, a.args[2], "error register");
    if (f.error_register > 0xFF) bad(a.spec, "error register must be 0..255");
  } else {
    return false;
  }
  return true;
}

// The faults only the simulated driver injects; false: not one of them.
bool read_process_fault(const std::string& kind, const FaultArgs& a, FaultSpec& f) {
  if (kind == "noise") {
    f.kind = FaultKind::kNoise;
    a.need(2, 3, "noise@TIME:CHANNEL:SD[:DURATION]");
    f.channel = a.args[1];
    f.value = number(a.spec, a.args[2], "noise SD", 0.0);
    if (a.args.size() > 3) f.duration_s = seconds(a.spec, a.args[3], "duration");
  } else if (kind == "nan") {
    f.kind = FaultKind::kNan;
    a.need(1, 2, "nan@TIME:CHANNEL[:DURATION]");
    f.channel = a.args[1];
    if (a.args.size() > 2) f.duration_s = seconds(a.spec, a.args[2], "duration");
  } else if (kind == "offset") {
    f.kind = FaultKind::kOffset;
    a.need(2, 2, "offset@TIME:CHANNEL:OFFSET");
    f.channel = a.args[1];
    f.value = number(a.spec, a.args[2], "offset", -1e308);
  } else if (kind == "overrun") {
    f.kind = FaultKind::kOverrun;
    a.need(1, 2, "overrun@TIME:COUNT[:STALL_PERIODS]");
    f.count = integer(a.spec, a.args[1], "count");
    f.stall_periods = a.args.size() > 2 ? integer(a.spec, a.args[2], "stall periods") : 2;
    if (f.count < 1) bad(a.spec, "count must be at least 1");
    if (f.stall_periods < 1 || f.stall_periods > 400) bad(a.spec, "stall periods must be 1..400");
  } else if (kind == "supply") {
    f.kind = FaultKind::kSupply;
    a.need(1, 1, "supply@TIME:PRESSURE_PA");
    f.value = number(a.spec, a.args[1], "supply pressure", 0.0);
  } else if (kind == "burst") {
    f.kind = FaultKind::kBurst;
    a.need(1, 2, "burst@TIME:p1|p2[:K]");
    f.channel = a.args[1];
    if (f.channel != "p1" && f.channel != "p2") bad(a.spec, "chamber '" + f.channel + "' is not p1 or p2");
    // About 5.6 times the quarter car's rated valve: 100 l/min at 30 bar.
    f.value = a.args.size() > 2 ? number(a.spec, a.args[2], "orifice coefficient", 0.0) : 1e-6;
  } else {
    return false;
  }
  return true;
}

}  // namespace

bool fault_on_wire(FaultKind kind) {
  switch (kind) {
    case FaultKind::kSilence: case FaultKind::kDrop: case FaultKind::kLate: case FaultKind::kException:
    case FaultKind::kStuck: case FaultKind::kRail: case FaultKind::kHeartbeat: case FaultKind::kEmcy:
    case FaultKind::kHold: return true;
    default: return false;
  }
}

bool fault_in_process(FaultKind kind) {
  switch (kind) {
    case FaultKind::kStuck: case FaultKind::kRail: case FaultKind::kNoise: case FaultKind::kNan:
    case FaultKind::kOffset: case FaultKind::kOverrun: case FaultKind::kSupply: case FaultKind::kBurst: return true;
    default: return false;
  }
}

FaultSpec parse_fault_spec(const std::string& spec) {
  const auto at = spec.find('@');
  if (at == std::string::npos) bad(spec, "expected KIND@TIME[:ARG...]");
  const std::string kind = spec.substr(0, at);
  const FaultArgs a{spec, split(spec.substr(at + 1), ':')};
  FaultSpec f;
  f.text = spec;
  f.at_s = seconds(spec, a.args.at(0), "time");
  if (!read_wire_fault(kind, a, f) && !read_process_fault(kind, a, f)) {
    bad(spec, "unknown kind '" + kind +
                  "' (silence, drop, late, exception, stuck, rail, heartbeat, emcy, hold, noise, nan, offset, overrun, "
                  "supply, burst)");
  }
  if (f.channel.empty() && (f.kind == FaultKind::kException || f.kind == FaultKind::kStuck || f.kind == FaultKind::kRail ||
                            f.kind == FaultKind::kNoise || f.kind == FaultKind::kNan || f.kind == FaultKind::kOffset)) {
    bad(spec, "needs a channel name");
  }
  return f;
}

}  // namespace rigctl
