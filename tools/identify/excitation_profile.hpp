// The demand of an identification run: the config's lead-in to the
// operating point (from where the rig stands when `start: measured`), a
// settling hold there, the excitation table added to it tick by tick, then
// the operating point again until the run's controlled stop.
#pragma once

#include <memory>
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

// Several channels' signals, each after its own lead-in, started on the
// same tick: a channel with a shorter lead-in holds its operating point the
// longer (settle_s plus the difference to the longest lead-in).
class AlignedExcitation {
 public:
  AlignedExcitation(std::vector<LeadIn> leads, std::vector<std::vector<double>> signals, double settle_s,
                    double period_s, double tail_s);
  std::unique_ptr<ExcitationProfile> profile(std::size_t channel) const;
  // How long the channel holds its operating point between its lead-in and its signal [s].
  double hold_s(std::size_t channel) const { return settle_s_ + longest_s_ - leads_.at(channel).duration(); }

 private:
  std::vector<LeadIn> leads_;
  std::vector<std::vector<double>> signals_;
  double settle_s_, period_s_, tail_s_, longest_s_ = 0.0;
};

}  // namespace rigctl
