// Per-rig factories of the diagnosis sub-models; make_rig_model (tools/diagnosis/model.hpp)
// dispatches on the rig kind. One file per rig kind where it grows large.
#pragma once

#include <memory>

#include "config/rig_config.hpp"
#include "tools/diagnosis/model.hpp"

namespace rigctl::diag {

// The rig config at `path` for a replay of `rig`: a RunFileError (bad
// input) when it is another rig's config.
RigConfig load_replay_config(const std::string& path, RigKind rig);

// tools/diagnosis/models/quarter_car.cpp: seed 000's rig, two sub-models in one (the
// actuator in the PI loop, the suspension driven by the measured road).
std::unique_ptr<RigModel> make_quarter_car_model(const RunFile& run, const RigModelOptions& options);
// tools/diagnosis/models/pneumatic_rotary.cpp: closed-loop replay of theta_d through the P+V+dP
// controller and the pneumatic rotary plant (seed 002).
std::unique_ptr<RigModel> make_pneumatic_rotary_model(const RunFile& run, const RigModelOptions& options);
// tools/diagnosis/models/half_car.cpp: the 4-DOF half car (seed 001) driven by the
// measured road and actuator forces.
std::unique_ptr<RigModel> make_half_car_model(const RunFile& run, const RigModelOptions& options);

}  // namespace rigctl::diag
