// Placeholder until this rig's hidden-effect generator lands (helper in progress).
#include <stdexcept>

#include "tools/hidden_effects_rigs.hpp"

namespace rigctl {

const RigEffectGenerator& pneumatic_rotary_effect_generator() {
  throw std::invalid_argument("hidden-effect generator for 'pneumatic_rotary' is not implemented yet");
}

}  // namespace rigctl
