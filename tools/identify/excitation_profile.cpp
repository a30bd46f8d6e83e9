#include "tools/identify/excitation_profile.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace rigctl {

LeadIn lead_in_to(const RigConfig& config, double operating_point) {
  const ProfileConfig& p = config.profile;
  return LeadIn{p.start, operating_point, p.hold_s, p.ramp_rate > 0.0 ? p.ramp_rate : config.safety.setpoint_rate};
}

ExcitationProfile::ExcitationProfile(LeadIn lead_in, double settle_s, std::vector<double> excitation,
                                     double period_s, double tail_s)
    : lead_in_(lead_in), settle_s_(settle_s), excitation_(std::move(excitation)), period_s_(period_s),
      tail_s_(tail_s) {}

double ExcitationProfile::at(double t) const noexcept {
  const double t_excitation = t - excitation_start_s();
  if (t_excitation < 0.0) return lead_in_.at(t);
  // Profile times are whole ticks (nanosecond integers): round, do not floor.
  const auto i = static_cast<std::size_t>(std::llround(t_excitation / period_s_));
  return lead_in_.target + (i < excitation_.size() ? excitation_[i] : 0.0);
}

double ExcitationProfile::duration() const noexcept {
  return excitation_start_s() + static_cast<double>(excitation_.size()) * period_s_ + tail_s_;
}

AlignedExcitation::AlignedExcitation(std::vector<LeadIn> leads, std::vector<std::vector<double>> signals,
                                     double settle_s, double period_s, double tail_s)
    : leads_(std::move(leads)), signals_(std::move(signals)), settle_s_(settle_s), period_s_(period_s), tail_s_(tail_s) {
  for (const LeadIn& l : leads_) longest_s_ = std::max(longest_s_, l.duration());
}

std::unique_ptr<ExcitationProfile> AlignedExcitation::profile(std::size_t channel) const {
  return std::make_unique<ExcitationProfile>(leads_.at(channel), hold_s(channel), signals_.at(channel), period_s_,
                                             tail_s_);
}

}  // namespace rigctl
