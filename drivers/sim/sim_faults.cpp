#include "drivers/sim/sim_faults.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "plant/quarter_car/quarter_car_plant.hpp"
#include "plant/simulated_plant.hpp"

namespace rigctl {

namespace {

[[noreturn]] void bad(const FaultSpec& f, const std::string& why) {
  throw std::invalid_argument("fault '" + f.text + "': " + why);
}

bool is_sensor_fault(FaultKind k) {
  return k == FaultKind::kStuck || k == FaultKind::kRail || k == FaultKind::kNoise || k == FaultKind::kNan ||
         k == FaultKind::kOffset;
}

}  // namespace

SimFaults::SimFaults(const std::vector<FaultSpec>& specs, const ChannelLayout& layout,
                     const std::vector<SensorSpec>& sensors, SimulatedPlant& plant, double period_s, uint64_t seed)
    : quarter_car_(dynamic_cast<QuarterCarPlant*>(&plant)), period_s_(period_s), seed_(seed) {
  for (const auto& f : specs) {
    if (!fault_in_process(f.kind)) {
      bad(f, "acts on the wire: inject it with `rigctl rig-sim --fault` and a modbus driver");
    }
    Entry e;
    e.spec = f;
    e.start_tick = std::llround(f.at_s / period_s);
    if (f.duration_s > 0.0) e.end_tick = e.start_tick + std::max<int64_t>(1, std::llround(f.duration_s / period_s));
    if (is_sensor_fault(f.kind)) {
      e.channel = layout.input_index(f.channel);
      if (e.channel < 0) {
        std::string names;
        for (const auto& c : layout.inputs) names += (names.empty() ? "" : ", ") + c.name;
        bad(f, "no input channel '" + f.channel + "' (inputs: " + names + ")");
      }
      if (f.kind == FaultKind::kRail) {
        const SensorSpec& s = sensors.at(static_cast<std::size_t>(e.channel));
        if (s.bits <= 0) bad(f, "channel '" + f.channel + "' has no ADC range (sensors." + f.channel + ".bits) to sit at");
        e.rail = s.range_max;  // the top code: an open input floats to the positive rail
      }
    }
    if ((f.kind == FaultKind::kSupply || f.kind == FaultKind::kBurst) && quarter_car_ == nullptr) {
      bad(f, "needs the quarter_car plant (its hydraulic supply and chambers)");
    }
    entries_.push_back(e);
  }
  injected_at_ = std::make_unique<std::atomic<int64_t>[]>(entries_.size());
  reported_.assign(entries_.size(), false);
  reset();
}

void SimFaults::reset() noexcept {
  rng_.seed(seed_ ^ 0x5eed'fa17ULL);
  for (std::size_t i = 0; i < entries_.size(); ++i) {
    auto& e = entries_[i];
    e.stalls_done = 0;
    e.holding = false;
    e.plant_applied = false;
    injected_at_[i].store(-1, std::memory_order_relaxed);
  }
}

void SimFaults::mark(std::size_t i, int64_t tick) noexcept {
  if (injected_at_[i].load(std::memory_order_relaxed) < 0) injected_at_[i].store(tick, std::memory_order_release);
}

void SimFaults::apply_to_plant(int64_t tick) noexcept {
  for (std::size_t i = 0; i < entries_.size(); ++i) {
    auto& e = entries_[i];
    if (e.plant_applied || tick < e.start_tick) continue;
    if (e.spec.kind == FaultKind::kSupply) {
      quarter_car_->set_supply_pressure(e.spec.value);
    } else if (e.spec.kind == FaultKind::kBurst) {
      quarter_car_->set_chamber_leak(e.spec.channel == "p1" ? 1 : 2, e.spec.value);
    } else {
      continue;
    }
    e.plant_applied = true;
    mark(i, tick);
  }
}

int SimFaults::stall_periods(int64_t tick) noexcept {
  for (std::size_t i = 0; i < entries_.size(); ++i) {
    auto& e = entries_[i];
    if (e.spec.kind != FaultKind::kOverrun || tick < e.start_tick || e.stalls_done >= e.spec.count) continue;
    ++e.stalls_done;
    mark(i, tick);
    return e.spec.stall_periods;
  }
  return 0;
}

void SimFaults::apply_to_sample(int64_t tick, Sample& s) noexcept {
  for (std::size_t i = 0; i < entries_.size(); ++i) {
    auto& e = entries_[i];
    if (e.channel < 0 || tick < e.start_tick || tick >= e.end_tick) continue;
    double& v = s.value[static_cast<std::size_t>(e.channel)];
    switch (e.spec.kind) {
      case FaultKind::kStuck:
        if (!e.holding) {
          e.held = v;  // frozen at the reading the fault found
          e.holding = true;
        }
        v = e.held;
        break;
      case FaultKind::kRail: v = e.rail; break;
      case FaultKind::kNoise: v += e.spec.value * standard_normal(rng_); break;
      case FaultKind::kNan: v = std::numeric_limits<double>::quiet_NaN(); break;
      case FaultKind::kOffset: v += e.spec.value; break;
      default: break;
    }
    mark(i, tick);
  }
}

std::vector<std::string> SimFaults::take_new_reports() {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < entries_.size(); ++i) {
    const int64_t tick = injected_at_[i].load(std::memory_order_acquire);
    if (tick < 0 || reported_[i]) continue;
    reported_[i] = true;
    std::ostringstream os;
    os << "sim: fault " << entries_[i].spec.text << " injected at t = " << static_cast<double>(tick) * period_s_
       << " s (tick " << tick << ")";
    out.push_back(os.str());
  }
  return out;
}

int64_t SimFaults::injected_count() const noexcept {
  int64_t n = 0;
  for (std::size_t i = 0; i < entries_.size(); ++i) n += injected_at_[i].load(std::memory_order_relaxed) >= 0 ? 1 : 0;
  return n;
}

}  // namespace rigctl
