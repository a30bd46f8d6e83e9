// The controller that ran, read from the record: a closed-loop replay needs
// the gains the rig used, and a run file need not say them (another tool's
// records, a rig retuned since its config was written). The control laws'
// forms are known, so their gains follow from the recorded command by least
// squares on the law's terms; the config's gains are kept unless the record
// fits other gains clearly better (docs/diagnosis.md 4).
#pragma once

#include <string>
#include <vector>

#include "rt/control/pi_controller.hpp"
#include "rt/control/pvp_controller.hpp"

namespace rigctl::diag {

// u_k = kp e_k + ki Ts sum_{j<=k} e_j, e = x_ref - x_r, on unsaturated samples
// before the first saturation. Returns a sentence for the validation text.
std::string calibrate_pi(PiConfig& pi, const std::vector<double>& x_ref, const std::vector<double>& x_r,
                         const std::vector<double>& u);

// u = ke (theta_d - theta) - kp P - kv omega_f with the controller's own
// velocity filter and pressure term P (dp, or its high-passed form).
std::string calibrate_pvp(PvpConfig& pvp, const std::vector<double>& theta_d, const std::vector<double>& theta,
                          const std::vector<double>& dp, const std::vector<double>& u);

}  // namespace rigctl::diag
