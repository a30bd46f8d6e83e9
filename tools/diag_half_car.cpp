// Placeholder until the half-car sub-model lands (helper in progress).
#include "tools/diag_rigs.hpp"

namespace rigctl::diag {

std::unique_ptr<RigModel> make_half_car_model(const RunFile&, const RigModelOptions&) {
  throw RunFileError("diagnosis of rig kind 'half_car' is not implemented yet");
}

}  // namespace rigctl::diag
