#include "rt/procedure/procedure_runner.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rigctl {

namespace {

constexpr double kTwoPi = 2.0 * M_PI;

// Haversine from a to b, s in [0, 1]: zero slope at both ends.
double haversine(double a, double b, double s) noexcept { return a + (b - a) * 0.5 * (1.0 - std::cos(M_PI * s)); }

int64_t ticks_for(double distance, double rate, double period_s) noexcept {
  if (!(rate > 0.0)) return 0;
  return static_cast<int64_t>(std::ceil(std::fabs(distance) / rate / period_s));
}

bool cyclic(StepKind k) noexcept { return k == StepKind::kSine || k == StepKind::kBlocks; }

double rows_time_s(const StepSpec& s, std::size_t from_row) noexcept {
  double t = 0.0;
  for (std::size_t r = from_row; r < s.rows.size(); ++r) t += static_cast<double>(s.rows[r].cycles) / s.rows[r].frequency_hz;
  return t;
}

// One step's nominal duration; a ramp at a rate counts 0 (its distance
// depends on where it starts).
double nominal_time_s(const StepSpec& s, double period_s) noexcept {
  switch (s.kind) {
    case StepKind::kRamp: return s.rate > 0.0 ? 0.0 : s.time_s;
    case StepKind::kHold: return s.time_s;
    case StepKind::kSine:  // and its ramp-in cycle (peak_valley has none)
      return rows_time_s(s, 0) + (s.compensation.kind == Compensation::kPeakValley ? 0.0 : 1.0 / s.rows[0].frequency_hz);
    case StepKind::kBlocks: return static_cast<double>(s.repeats) * rows_time_s(s, 0);
    case StepKind::kDrive: return static_cast<double>(s.repeats) * static_cast<double>(s.drive.size()) * period_s;
    default: return 0.0;
  }
}

}  // namespace

ProcedureRunner::ProcedureRunner(const ProcedureSpec& spec, double period_s, int feedback_input)
    : spec_(spec), period_s_(period_s), feedback_input_(feedback_input) {
  if (spec.rainflow_channels.size() > kMaxRainflowChannels) {
    throw std::invalid_argument("procedure: at most " + std::to_string(kMaxRainflowChannels) + " rainflow channels");
  }
  int depth = 0;
  for (const auto& s : spec.steps) {
    if (s.rows.size() > kMaxBlockRows) {
      throw std::invalid_argument("procedure: " + s.name + " has more than " + std::to_string(kMaxBlockRows) + " rows");
    }
    depth += s.kind == StepKind::kRepeatBegin ? 1 : (s.kind == StepKind::kRepeatEnd ? -1 : 0);
    if (depth > kMaxRepeatDepth) throw std::invalid_argument("procedure: repeats nested deeper than " + std::to_string(kMaxRepeatDepth));
  }
  // Nominal durations: each group's body from the innermost out (an end
  // marker closes the innermost open group).
  const std::size_t n = spec.steps.size();
  step_time_s_.assign(n, 0.0);
  body_time_s_.assign(n, 0.0);
  group_end_.assign(n, static_cast<int>(n));
  std::vector<int> open;
  for (std::size_t i = 0; i < n; ++i) {
    const StepSpec& s = spec.steps[i];
    step_time_s_[i] = nominal_time_s(s, period_s);
    if (s.kind == StepKind::kRepeatBegin) {
      open.push_back(static_cast<int>(i));
    } else if (s.kind == StepKind::kRepeatEnd && !open.empty()) {
      const auto b = static_cast<std::size_t>(open.back());
      open.pop_back();
      group_end_[b] = static_cast<int>(i);
      double body = 0.0;
      for (std::size_t j = b + 1; j < i; ++j) {
        if (spec.steps[j].kind == StepKind::kRepeatBegin) {
          body += static_cast<double>(spec.steps[j].repeats) * body_time_s_[j];
          j = static_cast<std::size_t>(group_end_[j]);
        } else {
          body += step_time_s_[j];
        }
      }
      body_time_s_[b] = body;
    }
  }
  state_.status.active = true;
  state_.rainflow_channels = static_cast<uint32_t>(spec.rainflow_channels.size());
  // The rainflow matrix spans the programmed levels with a 20 % margin (a
  // cycle outside lands in the edge bin; its damage is exact anyway).
  double lo = 0.0, hi = 0.0, ref = spec.reference_range;
  bool any = false;
  for (const auto& s : spec.steps) {
    for (const auto& r : s.rows) {
      lo = any ? std::min(lo, r.mean - r.amplitude) : r.mean - r.amplitude;
      hi = any ? std::max(hi, r.mean + r.amplitude) : r.mean + r.amplitude;
      if (!(ref > 0.0)) ref = 2.0 * r.amplitude;
      any = true;
    }
  }
  const double margin = 0.2 * std::max(hi - lo, 1e-3);
  for (std::size_t i = 0; i < spec.rainflow_channels.size(); ++i) {
    rainflow_[i].configure(lo - margin, hi + margin, spec.basquin_exponent, ref > 0.0 ? ref : 1.0);
  }
}

void ProcedureRunner::restore(const ProcedureRecovery& r) noexcept {
  state_ = r;
  state_.status.active = true;
  sequence_ = r.sequence;
  for (std::size_t i = 0; i < spec_.rainflow_channels.size() && i < r.rainflow_channels; ++i) {
    const RainflowResidue& res = r.rainflow[i];
    rainflow_[i].counter().restore(res.points.data(), res.size, res.has_pending, res.pending, res.direction);
    rainflow_[i].committed().set_data(res.committed);
  }
  started_ = true;  // the next start continues the recovered step
  after_step_s_ = steps_after_s();
  update_time_left();
}

void ProcedureRunner::recovery(ProcedureRecovery& out) noexcept {
  recovery_due_ = false;  // taken: a held rig (the runner not asked) offers none every tick
  out = state_;
  out.sequence = ++sequence_;
  for (std::size_t i = 0; i < spec_.rainflow_channels.size(); ++i) {
    const RainflowCounter& c = rainflow_[i].counter();
    RainflowResidue& res = out.rainflow[i];
    res.size = static_cast<uint32_t>(c.residue_size());
    for (std::size_t k = 0; k < c.residue_size(); ++k) res.points[k] = c.residue_point(k);
    res.has_pending = c.has_pending();
    res.pending = c.pending();
    res.direction = static_cast<int8_t>(c.direction());
    res.committed = rainflow_[i].committed().data();
  }
}

// ---- starting and moving between steps

void ProcedureRunner::start(double present) noexcept {
  last_demand_ = present;
  if (!started_) {
    started_ = true;
    enter_step(0, present);
    return;
  }
  ProcedureStatus& st = state_.status;
  if (st.phase == ProcedurePhase::kDone) return;
  if (st.phase == ProcedurePhase::kEndLevel) {
    begin_end_level();
    return;
  }
  switch (step().kind) {
    case StepKind::kRamp: st.level = present; ramp_tick_ = 0; break;  // the ramp again, from here
    case StepKind::kHold:
    case StepKind::kSine:
    case StepKind::kBlocks:
    case StepKind::kDrive: begin_approach(present); break;
    default: break;
  }
}

void ProcedureRunner::enter_step(int index, double present) noexcept {
  ProcedureStatus& st = state_.status;
  recovery_due_ = true;
  // Steps that take no time (repeat markers) are walked at once; the
  // procedure has a finite number of them between two steps that take time.
  for (int guard = 0; guard <= static_cast<int>(spec_.steps.size()) * (kMaxRepeatDepth + 1); ++guard) {
    if (index >= static_cast<int>(spec_.steps.size())) {
      st.phase = ProcedurePhase::kDone;
      return;
    }
    st.step = index;
    st.step_cycles = st.row_cycles = st.pass = st.step_ticks = 0;
    st.row = 0;
    st.level = present;
    const StepSpec& s = step();
    if (s.kind == StepKind::kRepeatBegin) {
      st.repeat_begin[static_cast<std::size_t>(st.repeat_depth)] = index;
      st.repeat_done[static_cast<std::size_t>(st.repeat_depth)] = 0;
      ++st.repeat_depth;
      ++index;
      continue;
    }
    if (s.kind == StepKind::kRepeatEnd) {
      const auto top = static_cast<std::size_t>(st.repeat_depth - 1);
      const int begin = st.repeat_begin[top];
      if (++st.repeat_done[top] < spec_.steps[static_cast<std::size_t>(begin)].repeats) {
        index = begin + 1;
      } else {
        --st.repeat_depth;
        ++index;
      }
      continue;
    }
    // A new step: its compensation and detector reference start afresh.
    state_.reference = PeakValleyReference{};
    st.comp_gain = 1.0;
    st.comp_phase = st.comp_mean = 0.0;
    for (std::size_t r = 0; r < s.rows.size(); ++r) {
      state_.peak_command[r] = s.rows[r].mean + s.rows[r].amplitude;
      state_.valley_command[r] = s.rows[r].mean - s.rows[r].amplitude;
    }
    ramp_tick_ = 0;
    after_step_s_ = steps_after_s();
    if (s.kind == StepKind::kRamp || s.kind == StepKind::kHold) {
      st.phase = ProcedurePhase::kRun;
    } else {
      begin_approach(present);
    }
    return;
  }
  st.phase = ProcedurePhase::kDone;
}

// From the present demand to where the step starts (or continues).
void ProcedureRunner::begin_approach(double present) noexcept {
  ProcedureStatus& st = state_.status;
  const StepSpec& s = step();
  double target = present;
  switch (s.kind) {
    case StepKind::kSine:
      target = s.compensation.kind == Compensation::kPeakValley ? state_.valley_command[0] : s.rows[0].mean + st.comp_mean;
      break;
    case StepKind::kBlocks: target = state_.valley_command[row_index()]; break;
    case StepKind::kDrive: target = s.drive.front(); st.step_ticks = 0; break;
    case StepKind::kHold: target = st.level; break;
    default: break;
  }
  st.phase = ProcedurePhase::kApproach;
  ramp_from_ = present;
  ramp_to_ = target;
  ramp_ticks_ = ticks_for(target - present, s.rate > 0.0 ? s.rate : spec_.ramp_rate, period_s_);
  ramp_tick_ = 0;
}

void ProcedureRunner::begin_cyclic() noexcept {
  ProcedureStatus& st = state_.status;
  const StepSpec& s = step();
  cycle_phase_ = 0.0;
  cycle_seen_ = false;
  fit_.reset();
  tp_direction_ = 0;
  peak_pending_row_ = valley_pending_row_ = -1;
  if (s.kind == StepKind::kSine && s.compensation.kind != Compensation::kPeakValley) {
    // The amplitude comes in from zero over one cycle: no step in the demand.
    st.phase = ProcedurePhase::kRampIn;
    blending_ = true;
    from_gain_ = 0.0;
    from_phase_ = st.comp_phase;
    from_mean_ = st.comp_mean;
    measured_cycles_ = 0;
    return;
  }
  st.phase = ProcedurePhase::kRun;
  half_start_ = last_demand_;
  half_end_ = state_.peak_command[row_index()];
  in_down_half_ = false;
}

void ProcedureRunner::finish_step() noexcept {
  recovery_due_ = true;
  block_ended();
  if (step().has_end_level) {
    begin_end_level();
    return;
  }
  enter_step(state_.status.step + 1, last_demand_);
}

void ProcedureRunner::begin_end_level() noexcept {
  ProcedureStatus& st = state_.status;
  st.phase = ProcedurePhase::kEndLevel;
  ramp_from_ = last_demand_;
  ramp_to_ = step().end_level;
  ramp_ticks_ = ticks_for(ramp_to_ - ramp_from_, spec_.ramp_rate, period_s_);
  ramp_tick_ = 0;
}

// ---- one tick

double ProcedureRunner::next(const Sample& sample, double feedback) noexcept {
  recovery_due_ = false;
  new_trip_ = Event{};
  if (!started_) start(feedback);
  double d = last_demand_;
  // A step that ends without taking time hands the tick to the next one;
  // each pass either gives a demand or moves to a later step.
  for (int guard = 0; guard < 8; ++guard) {
    Tick t = Tick::kDemand;
    ProcedureStatus& st = state_.status;
    switch (st.phase) {
      case ProcedurePhase::kDone: d = last_demand_; break;
      case ProcedurePhase::kApproach: t = approach_tick(d); break;
      case ProcedurePhase::kEndLevel: t = end_level_tick(d); break;
      case ProcedurePhase::kRampIn:
      case ProcedurePhase::kRun:
        switch (step().kind) {
          case StepKind::kRamp: t = ramp_tick(d); break;
          case StepKind::kHold: t = hold_tick(d); break;
          case StepKind::kDrive: t = drive_tick(d); break;
          case StepKind::kSine:
            // A sine under peak_valley runs as a one-row block program.
            t = step().compensation.kind == Compensation::kPeakValley ? blocks_tick(sample, feedback, d)
                                                                        : sine_tick(sample, feedback, d);
            break;
          case StepKind::kBlocks: t = blocks_tick(sample, feedback, d); break;
          default: t = Tick::kMoved; break;
        }
        break;
    }
    if (t == Tick::kDemand) break;
  }
  if (state_.status.phase != ProcedurePhase::kDone) count_rainflow(sample);
  update_time_left();
  last_demand_ = d;
  return d;
}

ProcedureRunner::Tick ProcedureRunner::approach_tick(double& d) noexcept {
  if (ramp_tick_ >= ramp_ticks_) {
    last_demand_ = ramp_to_;
    const StepKind k = step().kind;
    if (cyclic(k)) {
      begin_cyclic();
    } else {
      state_.status.phase = ProcedurePhase::kRun;
    }
    return Tick::kMoved;
  }
  ++ramp_tick_;
  d = ramp_from_ + (ramp_to_ - ramp_from_) * static_cast<double>(ramp_tick_) / static_cast<double>(ramp_ticks_);
  state_.status.wanted = d;
  return Tick::kDemand;
}

ProcedureRunner::Tick ProcedureRunner::end_level_tick(double& d) noexcept {
  if (ramp_tick_ >= ramp_ticks_) {
    last_demand_ = ramp_to_;
    enter_step(state_.status.step + 1, ramp_to_);
    return Tick::kMoved;
  }
  ++ramp_tick_;
  d = ramp_from_ + (ramp_to_ - ramp_from_) * static_cast<double>(ramp_tick_) / static_cast<double>(ramp_ticks_);
  state_.status.wanted = d;
  return Tick::kDemand;
}

ProcedureRunner::Tick ProcedureRunner::ramp_tick(double& d) noexcept {
  ProcedureStatus& st = state_.status;
  const StepSpec& s = step();
  const int64_t n = s.rate > 0.0 ? ticks_for(s.level - st.level, s.rate, period_s_)
                                 : static_cast<int64_t>(std::ceil(s.time_s / period_s_));
  if (ramp_tick_ >= n) {
    last_demand_ = s.level;
    finish_step();
    return Tick::kMoved;
  }
  ++ramp_tick_;
  st.step_ticks = ramp_tick_;
  d = st.level + (s.level - st.level) * static_cast<double>(ramp_tick_) / static_cast<double>(n);
  st.wanted = d;
  return Tick::kDemand;
}

ProcedureRunner::Tick ProcedureRunner::hold_tick(double& d) noexcept {
  ProcedureStatus& st = state_.status;
  if (st.step_ticks >= static_cast<int64_t>(std::ceil(step().time_s / period_s_))) {
    finish_step();
    return Tick::kMoved;
  }
  ++st.step_ticks;
  d = st.wanted = st.level;
  return Tick::kDemand;
}

ProcedureRunner::Tick ProcedureRunner::drive_tick(double& d) noexcept {
  ProcedureStatus& st = state_.status;
  const StepSpec& s = step();
  if (st.step_ticks >= static_cast<int64_t>(s.drive.size())) {
    // A pass ended: it is the drive's test cycle.
    st.step_ticks = 0;
    ++st.pass;
    ++st.step_cycles;
    ++st.total_cycles;
    recovery_due_ = true;
    block_ended();
    if (st.pass >= s.repeats) {
      finish_step();
      return Tick::kMoved;
    }
  }
  d = st.wanted = s.drive[static_cast<std::size_t>(st.step_ticks)];
  ++st.step_ticks;
  return Tick::kDemand;
}

// ---- sine

ProcedureRunner::Tick ProcedureRunner::sine_tick(const Sample& s, double feedback, double& d) noexcept {
  ProcedureStatus& st = state_.status;
  const StepSpec& sp = step();
  const BlockRow& r = sp.rows[0];
  cycle_phase_ += r.frequency_hz * period_s_;
  if (cycle_phase_ >= 1.0) {
    cycle_phase_ -= 1.0;
    close_sine_cycle();
    if (close_cycle()) {
      finish_step();  // from the last cycle's end (last_demand_)
      return Tick::kMoved;
    }
  }
  const double theta = kTwoPi * cycle_phase_;
  double gain = st.comp_gain, phase = st.comp_phase, mean = st.comp_mean;
  if (blending_) {
    gain = from_gain_ + (gain - from_gain_) * cycle_phase_;
    phase = from_phase_ + (phase - from_phase_) * cycle_phase_;
    mean = from_mean_ + (mean - from_mean_) * cycle_phase_;
  }
  st.wanted = r.mean + r.amplitude * std::sin(theta);
  d = r.mean + mean + gain * r.amplitude * std::sin(theta + phase);
  fit_.add(theta, feedback);
  track_cycle_extremes(s, feedback);
  return Tick::kDemand;
}

// The fitted fundamental of the cycle just ended, and the correction for the
// next ones (amplitude_phase): measured cycles alternate with blend cycles.
void ProcedureRunner::close_sine_cycle() noexcept {
  ProcedureStatus& st = state_.status;
  const StepSpec& sp = step();
  const BlockRow& r = sp.rows[0];
  if (blending_) {
    // A blend cycle (or the ramp-in) is not measured: the command changed in it.
    blending_ = false;
    fit_.reset();
    measured_cycles_ = 0;
    return;
  }
  // Two cycles a measurement: one cycle's fit at 27 ticks (15 Hz) scatters
  // by 0.5 % of a 1 mm amplitude with the quarter car's 20 um sensor noise,
  // and a correction that follows the scatter never settles within 1 %.
  if (++measured_cycles_ < kMeasuredCycles) return;
  measured_cycles_ = 0;
  const Fundamental f = fit_.solve();
  fit_.reset();
  if (!f.valid) return;
  st.amplitude_error = r.amplitude > 0.0 ? f.amplitude / r.amplitude - 1.0 : 0.0;
  st.phase_error = wrap_pi(f.phase);
  if (sp.compensation.kind != Compensation::kAmplitudePhase || !(f.amplitude > 0.0)) return;
  const double k = sp.compensation.gain;
  from_gain_ = st.comp_gain;
  from_phase_ = st.comp_phase;
  from_mean_ = st.comp_mean;
  // Geometric in the gain (the loss is a ratio), linear in phase and mean.
  st.comp_gain *= std::pow(r.amplitude / f.amplitude, k);
  st.comp_phase = wrap_pi(st.comp_phase - k * st.phase_error);
  st.comp_mean += k * (r.mean - f.mean);
  blending_ = true;
  const double limit = sp.compensation.max_factor;
  if (st.comp_gain > limit || st.comp_gain < 1.0 / limit) {
    trip(EventCode::kCompensationLimit, feedback_input_, st.comp_gain, LimitAction::kStop);
  }
}

// Counts the cycle that ended; true when the step's cycles are done.
bool ProcedureRunner::close_cycle() noexcept {
  ProcedureStatus& st = state_.status;
  const StepSpec& sp = step();
  recovery_due_ = true;
  if (cycle_seen_) {
    st.peak = cycle_max_;
    st.valley = cycle_min_;
    if (st.phase == ProcedurePhase::kRun && sp.peak_valley.enabled) check_peak_valley(pv_max_, pv_min_);
  }
  cycle_seen_ = false;
  if (st.phase == ProcedurePhase::kRampIn) {
    ++st.ramp_in_cycles;
    st.phase = ProcedurePhase::kRun;
    return false;
  }
  ++st.step_cycles;
  ++st.total_cycles;
  if (sp.kind == StepKind::kSine) return st.step_cycles >= sp.rows[0].cycles;
  // blocks: the row, then the program's pass
  if (++st.row_cycles < row().cycles) return false;
  st.row_cycles = 0;
  if (++st.row < static_cast<int32_t>(sp.rows.size())) return false;
  st.row = 0;
  ++st.pass;
  block_ended();
  return st.pass >= sp.repeats;
}

// ---- blocks: valley -> peak -> valley, haversine halves between end levels

ProcedureRunner::Tick ProcedureRunner::blocks_tick(const Sample& s, double feedback, double& d) noexcept {
  ProcedureStatus& st = state_.status;
  cycle_phase_ += row().frequency_hz * period_s_;
  if (!in_down_half_ && cycle_phase_ >= 0.5) {
    // The commanded peak is passed: the next feedback peak is its answer.
    in_down_half_ = true;
    peak_pending_row_ = st.row;
    half_start_ = half_end_;
    half_end_ = state_.valley_command[row_index()];
  }
  if (cycle_phase_ >= 1.0) {
    cycle_phase_ -= 1.0;
    valley_pending_row_ = st.row;
    const double valley = half_end_;
    if (close_cycle()) {
      finish_step();  // from the last valley (last_demand_)
      return Tick::kMoved;
    }
    in_down_half_ = false;
    half_start_ = valley;
    half_end_ = state_.peak_command[row_index()];
  }
  const double s_half = in_down_half_ ? 2.0 * cycle_phase_ - 1.0 : 2.0 * cycle_phase_;
  d = haversine(half_start_, half_end_, s_half);
  const BlockRow& r = row();
  st.wanted = in_down_half_ ? haversine(r.mean + r.amplitude, r.mean - r.amplitude, s_half)
                            : haversine(r.mean - r.amplitude, r.mean + r.amplitude, s_half);
  st.comp_peak = state_.peak_command[row_index()];
  st.comp_valley = state_.valley_command[row_index()];
  if (step().compensation.kind == Compensation::kPeakValley) track_turning_points(feedback);
  track_cycle_extremes(s, feedback);
  return Tick::kDemand;
}

// Turning points of the feedback with a hysteresis of 10 % of the wanted
// range (noise and friction ripple are far smaller; a real reversal is the
// whole range): each confirmed peak or valley answers the commanded one
// passed last, and corrects its row's end level.
void ProcedureRunner::track_turning_points(double y) noexcept {
  const BlockRow& r = row();
  const double h = 0.2 * r.amplitude;
  if (tp_direction_ == 0) {
    tp_direction_ = 1;
    tp_extreme_ = y;
    return;
  }
  const bool rising = tp_direction_ > 0;
  if (rising ? y > tp_extreme_ : y < tp_extreme_) {
    tp_extreme_ = y;
    return;
  }
  if (std::fabs(y - tp_extreme_) < h) return;
  const double extreme = tp_extreme_;
  tp_direction_ = -tp_direction_;
  tp_extreme_ = y;
  const int pending = rising ? peak_pending_row_ : valley_pending_row_;
  if (pending < 0) return;
  (rising ? peak_pending_row_ : valley_pending_row_) = -1;
  const StepSpec& sp = step();
  const BlockRow& pr = sp.rows[static_cast<std::size_t>(pending)];
  const double wanted = rising ? pr.mean + pr.amplitude : pr.mean - pr.amplitude;
  auto& command = rising ? state_.peak_command : state_.valley_command;
  const auto i = static_cast<std::size_t>(pending);
  command[i] += sp.compensation.gain * (wanted - extreme);
  ProcedureStatus& st = state_.status;
  (rising ? st.peak : st.valley) = extreme;
  (rising ? st.peak_error : st.valley_error) = (extreme - wanted) / (2.0 * pr.amplitude);
  const double factor = (state_.peak_command[i] - state_.valley_command[i]) / (2.0 * pr.amplitude);
  const double limit = sp.compensation.max_factor;
  if (factor > limit || factor < 1.0 / limit) trip(EventCode::kCompensationLimit, feedback_input_, factor, LimitAction::kStop);
}

// ---- per cycle: extremes, the peak-valley change detector

void ProcedureRunner::track_cycle_extremes(const Sample& s, double feedback) noexcept {
  const int ch = step().peak_valley.channel;
  const double pv = ch >= 0 ? s.value[static_cast<std::size_t>(ch)] : feedback;
  if (!cycle_seen_) {
    cycle_max_ = cycle_min_ = feedback;
    pv_max_ = pv_min_ = pv;
    cycle_seen_ = true;
    return;
  }
  cycle_max_ = std::max(cycle_max_, feedback);
  cycle_min_ = std::min(cycle_min_, feedback);
  pv_max_ = std::max(pv_max_, pv);
  pv_min_ = std::min(pv_min_, pv);
}

void ProcedureRunner::check_peak_valley(double peak, double valley) noexcept {
  const PeakValleyDetectorSpec& d = step().peak_valley;
  PeakValleyReference& ref = state_.reference;
  if (state_.status.step_cycles < d.settle_cycles) return;
  if (!ref.taken) {
    ref.peak_sum += peak;
    ref.valley_sum += valley;
    if (++ref.taken_cycles >= d.reference_cycles) {
      ref.peak = ref.peak_sum / static_cast<double>(ref.taken_cycles);
      ref.valley = ref.valley_sum / static_cast<double>(ref.taken_cycles);
      ref.taken = true;
    }
    return;
  }
  const double range = std::max(ref.peak - ref.valley, 1e-12);
  const double change = std::max(std::fabs(peak - ref.peak), std::fabs(valley - ref.valley)) / range;
  state_.status.pv_change = change;
  ref.out_of_tolerance = change > d.tolerance ? ref.out_of_tolerance + 1 : 0;
  if (ref.out_of_tolerance == d.cycles) trip(EventCode::kPeakValleyChange, d.channel, change, d.action);
}

void ProcedureRunner::trip(EventCode code, int channel, double value, LimitAction action) noexcept {
  action_ = more_severe(action_, action);
  new_trip_ = Event{code, static_cast<int16_t>(channel), value, 0, static_cast<uint8_t>(action)};
}

void ProcedureRunner::count_rainflow(const Sample& s) noexcept {
  for (std::size_t i = 0; i < spec_.rainflow_channels.size(); ++i) {
    rainflow_[i].push(s.value[static_cast<std::size_t>(spec_.rainflow_channels[i])]);
  }
  if (!spec_.rainflow_channels.empty()) state_.status.damage = rainflow_[0].committed().damage();
}

// ---- operator requests and time left

void ProcedureRunner::block_ended() noexcept {
  if (!state_.status.stop_at_block_end) return;
  state_.status.stop_at_block_end = false;  // the recovery written at this end has it done
  stop_due_ = true;
}

void ProcedureRunner::update_time_left() noexcept {
  state_.status.time_left_s =
      state_.status.phase == ProcedurePhase::kDone ? 0.0 : present_step_left_s() + after_step_s_;
}

double ProcedureRunner::present_step_left_s() const noexcept {
  const ProcedureStatus& st = state_.status;
  const StepSpec& s = step();
  const auto ticks_s = [&](int64_t ticks) { return static_cast<double>(std::max<int64_t>(ticks, 0)) * period_s_; };
  if (st.phase == ProcedurePhase::kEndLevel) return ticks_s(ramp_ticks_ - ramp_tick_);
  const bool running = st.phase == ProcedurePhase::kRun || st.phase == ProcedurePhase::kRampIn;
  const double in_cycle = running ? cycle_phase_ : 0.0;
  switch (s.kind) {
    case StepKind::kRamp: return s.rate > 0.0 ? 0.0 : std::max(0.0, s.time_s - ticks_s(st.step_ticks));
    case StepKind::kHold: return std::max(0.0, s.time_s - ticks_s(st.step_ticks));
    case StepKind::kSine: {
      const BlockRow& r = s.rows[0];
      const double cycles = static_cast<double>(r.cycles - st.step_cycles) + (st.phase == ProcedurePhase::kRampIn ? 1.0 : 0.0);
      return std::max(0.0, (cycles - in_cycle) / r.frequency_hz);
    }
    case StepKind::kBlocks: {
      const BlockRow& r = row();
      const double in_row = std::max(0.0, (static_cast<double>(r.cycles - st.row_cycles) - in_cycle) / r.frequency_hz);
      return in_row + rows_time_s(s, row_index() + 1) +
             static_cast<double>(std::max<int64_t>(s.repeats - st.pass - 1, 0)) * rows_time_s(s, 0);
    }
    case StepKind::kDrive:
      return ticks_s((s.repeats - st.pass) * static_cast<int64_t>(s.drive.size()) - (running ? st.step_ticks : 0));
    default: return 0.0;
  }
}

// The steps after the present one: the rest of every open repeat group
// (its passes still to come) and everything after it.
double ProcedureRunner::steps_after_s() const noexcept {
  const ProcedureStatus& st = state_.status;
  const int n = static_cast<int>(spec_.steps.size());
  double t = 0.0;
  int depth = st.repeat_depth;
  for (int j = st.step + 1; j < n;) {
    const StepSpec& s = spec_.steps[static_cast<std::size_t>(j)];
    if (s.kind == StepKind::kRepeatBegin) {
      t += static_cast<double>(s.repeats) * body_time_s_[static_cast<std::size_t>(j)];
      j = group_end_[static_cast<std::size_t>(j)] + 1;
      continue;
    }
    if (s.kind == StepKind::kRepeatEnd && depth > 0) {
      const auto top = static_cast<std::size_t>(depth - 1);
      const auto begin = static_cast<std::size_t>(st.repeat_begin[top]);
      const int64_t more = spec_.steps[begin].repeats - st.repeat_done[top] - 1;
      t += static_cast<double>(std::max<int64_t>(more, 0)) * body_time_s_[begin];
      --depth;
    } else {
      t += step_time_s_[static_cast<std::size_t>(j)];
    }
    ++j;
  }
  return t;
}

}  // namespace rigctl
