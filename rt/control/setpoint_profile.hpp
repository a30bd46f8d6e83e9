// Demand signals for the loop. A profile is a pure function of rig time; the
// first-order filter that smooths steps (seed 000 passes its demand through
// one "to avoid test rig damage") is applied on top by FilteredProfile.
#pragma once

#include <memory>
#include <string>
#include <vector>

namespace rigctl {

class SetpointProfile {
 public:
  virtual ~SetpointProfile() = default;
  virtual double at(double t) const noexcept = 0;  // demand at rig time t [s], SI units
  virtual double duration() const noexcept = 0;    // natural length [s]
  // Begin from this position instead of the configured start (a run that
  // starts where the rig stands: no jump). Profiles without a lead-in ignore it.
  virtual void start_from(double /*position*/) noexcept {}
};

// Hold `start` for hold_s, then move to `target` at constant rate.
struct LeadIn {
  double start = 0.0;   // [m or rad]
  double target = 0.0;  // [m or rad]
  double hold_s = 1.0;
  double rate = 0.02;   // [unit/s], > 0
  double duration() const noexcept;
  double at(double t) const noexcept;
  // Start from `position` instead, arriving at the same time as configured
  // (the rate adapts): the run keeps its timing wherever the rig stood.
  void rebase(double position) noexcept;
};

// The paper's test: ramp to mid-stroke, then steps relative to it.
class RampStepsProfile final : public SetpointProfile {
 public:
  // steps: offsets from lead_in.target, each held for step_hold_s.
  RampStepsProfile(LeadIn lead_in, std::vector<double> steps, double step_hold_s);
  double at(double t) const noexcept override;
  double duration() const noexcept override;
  void start_from(double position) noexcept override { lead_in_.rebase(position); }
  double step_time(std::size_t i) const noexcept;  // when step i begins [s]
  std::size_t step_count() const noexcept { return steps_.size(); }

 private:
  LeadIn lead_in_;
  std::vector<double> steps_;
  double step_hold_s_;
};

// Lead-in, then centre + amplitude sin(2 pi f (t - t_lead)) for `cycles` cycles.
class SineProfile final : public SetpointProfile {
 public:
  SineProfile(LeadIn lead_in, double amplitude, double frequency_hz, double cycles);
  void start_from(double position) noexcept override { lead_in_.rebase(position); }
  double at(double t) const noexcept override;
  double duration() const noexcept override;

 private:
  LeadIn lead_in_;
  double amplitude_, frequency_hz_, cycles_;
};

// A demand table (t, value), linearly interpolated, held at its ends.
class TableProfile final : public SetpointProfile {
 public:
  TableProfile(std::vector<double> t, std::vector<double> value);
  // Reads a CSV with a header naming columns `t` and `column`. Throws
  // std::runtime_error naming the file, line and column on bad data.
  static TableProfile from_csv(const std::string& path, const std::string& column);
  double at(double t) const noexcept override;
  double duration() const noexcept override { return t_.back(); }

 private:
  std::vector<double> t_, value_;
};

// A constant demand for `duration` seconds: a regulator whose disturbance
// comes from elsewhere (the half car holds its body at rest while the road
// moves under it). Starts where it is told to, nothing to rebase.
class HoldProfile final : public SetpointProfile {
 public:
  HoldProfile(double value, double duration_s) : value_(value), duration_(duration_s) {}
  double at(double /*t*/) const noexcept override { return value_; }
  double duration() const noexcept override { return duration_; }

 private:
  double value_, duration_;
};

// Discrete first-order low-pass (exact for a piecewise-constant input):
// y_k = y_{k-1} + (1 - exp(-Ts/tau)) (x_k - y_{k-1}); tau = 0 passes through.
class FilteredProfile {
 public:
  FilteredProfile(std::unique_ptr<SetpointProfile> raw, double tau_s, double period_s);
  void reset() noexcept { primed_ = false; }
  // Start from the measured position: the lead-in ramps from there and the
  // filter starts there, so a run never begins with a step in demand.
  void start_from(double position) noexcept {
    raw_->start_from(position);
    y_ = position;
    primed_ = true;
  }
  // Called once per tick with increasing t.
  double next(double t) noexcept;
  const SetpointProfile& raw() const noexcept { return *raw_; }

 private:
  std::unique_ptr<SetpointProfile> raw_;
  double alpha_;
  double y_ = 0.0;
  bool primed_ = false;
};

}  // namespace rigctl
