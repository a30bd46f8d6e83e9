// The demand of an identification run: the config's lead-in to the
// operating point (from where the rig stands when `start: measured`), a
// settling hold there, the excitation table added to it tick by tick, then
// the operating point again until the run's controlled stop.
#pragma once

#include <vector>

#include "config/rig_config.hpp"
#include "rt/control/setpoint_profile.hpp"

namespace rigctl {

// The config's lead-in to `operating_point` (from where the rig stands with
// `start: measured`): its own approach to its test position, else the
// held-setpoint rate. Identification and the drive iteration share it.
LeadIn lead_in_to(const RigConfig& config, double operating_point);

class ExcitationProfile final : public SetpointProfile {
 public:
  // lead_in.target is the operating point; excitation: one value per tick.
  ExcitationProfile(LeadIn lead_in, double settle_s, std::vector<double> excitation, double period_s,
                    double tail_s);
  double at(double t) const noexcept override;
  double duration() const noexcept override;
  void start_from(double position) noexcept override { lead_in_.rebase(position); }

  double operating_point() const noexcept { return lead_in_.target; }
  double excitation_start_s() const noexcept { return lead_in_.duration() + settle_s_; }

 private:
  LeadIn lead_in_;
  double settle_s_;
  std::vector<double> excitation_;
  double period_s_;
  double tail_s_;
};

}  // namespace rigctl
