// Placeholder until this rig's hidden-effect generator lands (helper in progress).
#include <stdexcept>

#include "tools/hidden_effects_rigs.hpp"

namespace rigctl {

const RigEffectGenerator& half_car_effect_generator() {
  throw std::invalid_argument("hidden-effect generator for 'half_car' is not implemented yet");
}

}  // namespace rigctl
