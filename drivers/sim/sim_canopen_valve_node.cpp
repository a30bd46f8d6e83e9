// SimCanopenValve's behaviour: initialisation and resets, NMT, SDO, the PDOs
// by the dictionary's mapping, the device state machine, the spool, the
// heartbeats and the deadlines that fault the valve. Runs on the node's
// thread (or an injector's) with mutex_ held.
#include <algorithm>
#include <array>
#include <cmath>

#include "drivers/canopen/protocol/cia408.hpp"
#include "drivers/canopen/protocol/cob_id.hpp"
#include "drivers/canopen/protocol/emcy.hpp"
#include "drivers/sim/sim_canopen_valve.hpp"

namespace rigctl {

using namespace canopen;

namespace {

constexpr int64_t kMs = 1'000'000;
constexpr uint8_t kFaultErrorRegister = error_register::kGeneric | error_register::kCommunication;
constexpr uint16_t kEmcyHeartbeat = 0x8130;     // life guard / heartbeat error
constexpr uint16_t kEmcyPdoTooShort = 0x8210;   // PDO not processed due to length error
constexpr uint16_t kEmcyPdoTooLong = 0x8220;    // PDO length exceeded
constexpr uint16_t kEmcyRpdoTimeout = 0x8250;   // RPDO time-out

int64_t signed_raw(uint32_t value, PdoType t) {
  switch (t) {
    case PdoType::kI8: return static_cast<int8_t>(value);
    case PdoType::kI16: return static_cast<int16_t>(value);
    case PdoType::kI32: return static_cast<int32_t>(value);
    default: return value;
  }
}

}  // namespace

// ---------------------------------------------------------------- initialisation

void SimCanopenValve::power_on(int64_t now) {
  setpoint_ = 0.0;
  out_.clear();
  reset_communication(now, true);
}

void SimCanopenValve::reset_communication(int64_t now, bool whole_dictionary) {
  for (std::size_t i = 0; i < od_.size(); ++i) {
    if (whole_dictionary || od_defaults_[i].index < 0x2000) od_[i].value = od_defaults_[i].value;
  }
  if (whole_dictionary) {
    setpoint_ = 0.0;
    dsm_.power_on();
  } else {
    dsm_.clear_fault();
  }
  fault_.store(false, std::memory_order_release);
  producer_ = HeartbeatProducer(config_.node_id, 0);
  after_write(0x1016, 1, now);
  refresh_pdos();
  rpdo_deadline_ns_ = 0;
  set_nmt(NmtState::kBootUp);  // initialising: deaf and silent until the boot-up
  boot_until_ns_ = now + static_cast<int64_t>(config_.boot_delay_s * 1e9);
  if (boot_until_ns_ <= now) finish_boot(now);
}

void SimCanopenValve::finish_boot(int64_t now) {
  boot_until_ns_ = 0;
  queue(encode_heartbeat(config_.node_id, NmtState::kBootUp), now);
  ++stats_.boot_ups;
  set_nmt(NmtState::kPreOperational);
  after_write(0x1017, 0, now);  // the heartbeat starts after the boot-up
  tpdo_period_ns_ = static_cast<int64_t>(od(pdo_communication_index(PdoDirection::kTransmit, config_.actual_tpdo),
                                             kPdoEventTimerSub).value) * kMs;
  next_tpdo_ns_ = now;
}

// ---------------------------------------------------------------- frames

void SimCanopenValve::handle(const CanFrame& f, int64_t now) {
  CobInfo info;
  const Malformed m = check_frame(f, info);
  if (booting(now)) {
    if (m == Malformed::kNone && info.function == Function::kSdoRx && info.node == config_.node_id) {
      ++stats_.sdo_while_booting;
    }
    return;
  }
  if (m != Malformed::kNone) {
    ++stats_.malformed;
    return;
  }
  switch (info.function) {
    case Function::kNmt: handle_nmt(f, now); return;
    case Function::kHeartbeat: {
      Heartbeat hb;
      if (decode_heartbeat(f, hb) != Malformed::kNone) {
        ++stats_.malformed;
        return;
      }
      consumer_.on_heartbeat(hb, now);  // ignores other nodes than the configured master
      return;
    }
    case Function::kSdoRx:
      // CiA 301: no SDO in stopped.
      if (info.node == config_.node_id && nmt_state_ != NmtState::kStopped) handle_sdo(f, now);
      return;
    default:
      if (rpdo_.valid && f.id() == rpdo_.cob_id && nmt_state_ == NmtState::kOperational) handle_rpdo(f, now);
      return;
  }
}

void SimCanopenValve::handle_nmt(const CanFrame& f, int64_t now) {
  NmtMessage m;
  if (decode_nmt(f, m) != Malformed::kNone) {
    ++stats_.malformed;
    return;
  }
  if (m.node != 0 && m.node != config_.node_id) return;
  ++stats_.nmt_commands;
  switch (m.command) {
    case NmtCommand::kStart:
      set_nmt(NmtState::kOperational);
      next_tpdo_ns_ = now;
      rpdo_deadline_ns_ = 0;  // monitored from the first RPDO on
      break;
    case NmtCommand::kStop: set_nmt(NmtState::kStopped); break;
    case NmtCommand::kEnterPreOperational: set_nmt(NmtState::kPreOperational); break;
    case NmtCommand::kResetNode: reset_communication(now, true); break;
    case NmtCommand::kResetCommunication: reset_communication(now, false); break;
  }
}

void SimCanopenValve::handle_rpdo(const CanFrame& f, int64_t now) {
  if (f.len != rpdo_.mapping.byte_length()) {
    ++stats_.pdo_length_errors;
    od(0x1001, 0).value = kFaultErrorRegister;
    queue(encode_emcy({config_.node_id, f.len < rpdo_.mapping.byte_length() ? kEmcyPdoTooShort : kEmcyPdoTooLong,
                       kFaultErrorRegister, {}}),
          now);
    return;
  }
  std::array<int64_t, PdoMapping::kMaxEntries> raw{};
  if (decode_pdo_raw(rpdo_.mapping, f, raw) != Malformed::kNone) {
    ++stats_.malformed;
    return;
  }
  ++stats_.rpdos;
  for (std::size_t i = 0; i < rpdo_.mapping.size(); ++i) {
    const PdoEntry& e = rpdo_.mapping[i];
    OdEntry& target = od(e.index, e.subindex);
    target.value = static_cast<uint32_t>(raw[i]) & sdo_size_mask(target.size);
    after_write(e.index, e.subindex, now);
  }
  const uint32_t deadline_ms = od(pdo_communication_index(PdoDirection::kReceive, config_.setpoint_rpdo),
                                  kPdoEventTimerSub).value;
  rpdo_deadline_ns_ = deadline_ms > 0 ? now + static_cast<int64_t>(deadline_ms) * kMs : 0;
}

void SimCanopenValve::handle_sdo(const CanFrame& f, int64_t now) {
  const uint32_t writes = sdo_->writes();
  Malformed why = Malformed::kNone;
  const auto response = sdo_->on_frame(f, &why);
  if (why != Malformed::kNone) ++stats_.malformed;
  if (response && sdo_answers_to_lose_ > 0) {
    --sdo_answers_to_lose_;
  } else if (response) {
    queue(*response, now);
  }
  if (sdo_->writes() != writes) {
    ++stats_.sdo_writes;
    after_write(get_u16le(&f.data[1]), f.data[3], now);
  }
}

// Makes a written object take effect.
void SimCanopenValve::after_write(uint16_t index, uint8_t subindex, int64_t now) {
  const uint16_t rpdo_comm = pdo_communication_index(PdoDirection::kReceive, config_.setpoint_rpdo);
  const uint16_t tpdo_comm = pdo_communication_index(PdoDirection::kTransmit, config_.actual_tpdo);
  if (index == 0x1017) {
    producer_ = HeartbeatProducer(config_.node_id, od(0x1017, 0).value * kMs);
    if (!booting(now)) producer_.start(now);
  } else if (index == 0x1016 && subindex == 1) {
    const uint32_t entry = od(0x1016, 1).value;
    const auto master = static_cast<uint8_t>((entry >> 16) & 0x7F);
    consumer_ = HeartbeatConsumer(master, static_cast<int64_t>(entry & 0xFFFF) * kMs);
  } else if (index == cia408::kControlWord) {
    apply_control_word(static_cast<uint16_t>(od(index, 0).value), now);
  } else if (index == tpdo_comm && subindex == kPdoEventTimerSub) {
    const uint32_t ms = od(index, kPdoEventTimerSub).value;
    tpdo_period_ns_ = ms > 0 ? static_cast<int64_t>(ms) * kMs : static_cast<int64_t>(config_.tpdo_period_s * 1e9);
  } else if (index == cia408::kSplSetpoint && subindex == cia408::kValueSubindex) {
    setpoint_ = sdo_sign_extend(od(index, 1).value, 2) * spool_scale();
  }
  if (index == rpdo_comm || index == tpdo_comm || index == pdo_mapping_index(PdoDirection::kReceive, config_.setpoint_rpdo) ||
      index == pdo_mapping_index(PdoDirection::kTransmit, config_.actual_tpdo)) {
    refresh_pdos();
  }
}

void SimCanopenValve::refresh_pdos() {
  rpdo_ = pdo_from_dictionary(od_, PdoDirection::kReceive, config_.setpoint_rpdo);
  tpdo_ = pdo_from_dictionary(od_, PdoDirection::kTransmit, config_.actual_tpdo);
}

void SimCanopenValve::apply_control_word(uint16_t cw, int64_t now) {
  od(cia408::kControlWord, 0).value = cw;
  if (dsm_.on_control_word(cw)) {  // a fault reset
    fault_.store(false, std::memory_order_release);
    od(0x1001, 0).value = 0;
    queue(encode_emcy({config_.node_id, 0x0000, 0, {}}), now);
  }
}

// ---------------------------------------------------------------- time

void SimCanopenValve::enter_fail_safe(int64_t now, uint16_t emcy_code) {
  if (emcy_code == kEmcyHeartbeat) ++stats_.master_heartbeat_losses;
  fail_safe_ns_ = now;
  if (!dsm_.faulted()) {
    dsm_.fault();
    od(0x1001, 0).value = kFaultErrorRegister;
    queue(encode_emcy({config_.node_id, emcy_code, kFaultErrorRegister, {}}), now);
  }
  fault_.store(true, std::memory_order_release);
  // The CiA 301 default reaction to a communication error (0x1029).
  if (emcy_code == kEmcyHeartbeat && nmt_state_ == NmtState::kOperational) set_nmt(NmtState::kPreOperational);
}

void SimCanopenValve::watch_deadlines(int64_t now) {
  if (consumer_.poll(now) == HeartbeatConsumer::Event::kTimedOut) enter_fail_safe(now, kEmcyHeartbeat);
  if (rpdo_deadline_ns_ != 0 && now > rpdo_deadline_ns_) {
    rpdo_deadline_ns_ = 0;  // reported once; the next RPDO watches again
    if (nmt_state_ == NmtState::kOperational) {
      ++stats_.rpdo_timeouts;
      enter_fail_safe(now, kEmcyRpdoTimeout);
    }
  }
}

void SimCanopenValve::step(int64_t now) {
  const int64_t dt = std::max<int64_t>(0, now - last_step_ns_);
  last_step_ns_ = now;
  dsm_.step(now);
  if (boot_until_ns_ != 0 && now >= boot_until_ns_) finish_boot(now);
  if (!booting(now)) watch_deadlines(now);

  double target = 0.0;  // DISABLED, INIT, fault disabled: the hydraulic fail-safe null
  if (dsm_.active() && nmt_state_ == NmtState::kOperational && od(cia408::kDeviceMode, 0).value == 1) {
    target = std::clamp(setpoint_, -1.0, 1.0);
  } else if (dsm_.holding()) {
    target = std::clamp(sdo_sign_extend(od(cia408::kSplHoldSetpoint, 1).value, 2) * spool_scale(), -1.0, 1.0);
  }
  const double tau = config_.spool_time_constant_s;
  const double alpha = tau > 0.0 ? 1.0 - std::exp(-static_cast<double>(dt) * 1e-9 / tau) : 1.0;
  spool_state_ += (target - spool_state_) * alpha;
  spool_.store(spool_state_, std::memory_order_release);
  od(cia408::kSplActualValue, 1).value =
      static_cast<uint16_t>(static_cast<int16_t>(std::lround(spool_state_ * config_.spool_reference)));
  od(cia408::kStatusWord, 0).value = dsm_.status_word();
  if (config_.with_pressure) {
    const double counts = std::clamp(pressure_.load(std::memory_order_acquire) / config_.pressure_scale_pa, -32768.0, 32767.0);
    od(cia408::kPrsActualValue, 1).value = static_cast<uint16_t>(static_cast<int16_t>(std::lround(counts)));
  }
  if (booting(now)) return;
  if (auto hb = producer_.poll(now, nmt_state_)) {
    if (now >= miss_heartbeats_until_ns_) queue(*hb, now);
  }
  if (nmt_state_ == NmtState::kOperational && now >= next_tpdo_ns_) send_tpdo(now);
}

void SimCanopenValve::send_tpdo(int64_t now) {
  const int64_t period = tpdo_period_ns_ > 0 ? tpdo_period_ns_ : static_cast<int64_t>(config_.tpdo_period_s * 1e9);
  next_tpdo_ns_ = now - next_tpdo_ns_ > period ? now + period : next_tpdo_ns_ + period;  // no burst after a stall
  if (!tpdo_.valid) return;
  std::array<int64_t, PdoMapping::kMaxEntries> raw{};
  for (std::size_t i = 0; i < tpdo_.mapping.size(); ++i) {
    const PdoEntry& e = tpdo_.mapping[i];
    raw[i] = signed_raw(od(e.index, e.subindex).value, e.type);
  }
  CanFrame f;
  encode_pdo_raw(tpdo_.mapping, tpdo_.cob_id, std::span<const int64_t>(raw.data(), tpdo_.mapping.size()), f);
  queue(f, now);
}

}  // namespace rigctl
