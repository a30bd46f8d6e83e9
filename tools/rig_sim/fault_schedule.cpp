#include "tools/rig_sim/fault_schedule.hpp"

#include <stdexcept>

namespace rigctl {

namespace {

std::size_t daq_input_index(const ModbusDaqConfig& daq, const std::string& channel, const std::string& fault) {
  for (std::size_t i = 0; i < daq.inputs.size(); ++i) {
    if (daq.inputs[i].name == channel) return i;
  }
  throw std::invalid_argument("fault '" + fault + "': '" + channel + "' is not a DAQ input");
}

}  // namespace

FaultSchedule::FaultSchedule(std::vector<FaultSpec> faults, SimModbusDaq& daq, SimCanopenValve* valve, std::ostream& out)
    : faults_(std::move(faults)), started_(faults_.size(), false), ended_(faults_.size(), false), daq_(daq),
      valve_(valve), out_(out) {
  for (const auto& f : faults_) {
    if (!fault_on_wire(f.kind)) {
      throw std::invalid_argument("fault '" + f.text + "' is injected in the simulated driver: `rigctl run --fault` with driver: sim");
    }
    if ((f.kind == FaultKind::kHeartbeat || f.kind == FaultKind::kEmcy || f.kind == FaultKind::kHold) &&
        valve_ == nullptr) {
      throw std::invalid_argument("fault '" + f.text + "' needs the CANopen valve (--can-socket)");
    }
    if (f.kind == FaultKind::kException || f.kind == FaultKind::kStuck || f.kind == FaultKind::kRail) {
      daq_input_index(daq_.client_config(), f.channel, f.text);  // fail before running
    }
  }
}

void FaultSchedule::apply(double t) {
  for (std::size_t i = 0; i < faults_.size(); ++i) {
    const auto& f = faults_[i];
    if (!started_[i] && t >= f.at_s) {
      started_[i] = true;
      begin(f);
      out_ << "rig-sim: t = " << t << " s: fault " << f.text << "\n";
      out_.flush();
    }
    if (started_[i] && !ended_[i] && f.duration_s > 0.0 && t >= f.at_s + f.duration_s) {
      ended_[i] = true;
      end(f);
      out_ << "rig-sim: t = " << t << " s: fault " << f.text << " cleared\n";
      out_.flush();
    }
  }
}

void FaultSchedule::begin(const FaultSpec& f) {
  const auto cfg = daq_.client_config();
  switch (f.kind) {
    case FaultKind::kSilence: daq_.set_silent(true); break;
    case FaultKind::kDrop: daq_.drop_connections(); break;
    case FaultKind::kLate: daq_.set_reply_delay(f.delay_s); break;
    case FaultKind::kException: {
      const auto& p = cfg.inputs[daq_input_index(cfg, f.channel, f.text)].point;
      daq_.add_exception({p.unit_id, p.type, p.address, p.address + register_count(p.format) - 1, f.code});
      break;
    }
    case FaultKind::kStuck: daq_.set_stuck(daq_input_index(cfg, f.channel, f.text), true); break;
    case FaultKind::kRail: {
      // The top of the register's range: what an open-circuit transducer
      // drives the ADC to.
      const auto& p = cfg.inputs[daq_input_index(cfg, f.channel, f.text)].point;
      const double rail = p.format == DataFormat::kInt16 ? 32767.0
                          : p.format == DataFormat::kUint16 ? 65535.0
                          : p.format == DataFormat::kInt32 ? 2147483647.0
                          : p.format == DataFormat::kUint32 ? 4294967295.0
                                                             : 3.0e38;
      daq_.force_raw(daq_input_index(cfg, f.channel, f.text), rail);
      break;
    }
    case FaultKind::kHeartbeat: valve_->miss_heartbeats(f.duration_s > 0.0 ? f.duration_s : 1e9); break;
    case FaultKind::kEmcy:
      valve_->send_emcy(static_cast<uint16_t>(f.code), static_cast<uint8_t>(f.error_register));
      break;
    case FaultKind::kHold: valve_->drop_to_hold(f.duration_s > 0.0 ? f.duration_s : 1e9); break;
    default: break;  // not on the wire: refused by the constructor
  }
}

void FaultSchedule::end(const FaultSpec& f) {
  switch (f.kind) {
    case FaultKind::kSilence: daq_.set_silent(false); break;
    case FaultKind::kLate: daq_.set_reply_delay(0.0); break;
    default: break;  // one-off or until the end
  }
}

}  // namespace rigctl
