// The per-rig parts of the hidden-effect generator (tools/hidden_effects/<rig>.cpp);
// effect_generator() in tools/hidden_effects/make_run.cpp looks them up by rig kind.
#pragma once

#include "tools/hidden_effects/make_run.hpp"

namespace rigctl {

const RigEffectGenerator& quarter_car_effect_generator();
const RigEffectGenerator& pneumatic_rotary_effect_generator();
const RigEffectGenerator& half_car_effect_generator();
const RigEffectGenerator& two_poster_effect_generator();

}  // namespace rigctl
