// Placeholder until the pneumatic rotary sub-model lands (helper in progress).
#include "tools/diag_rigs.hpp"

namespace rigctl::diag {

std::unique_ptr<RigModel> make_pneumatic_rotary_model(const RunFile&, const RigModelOptions&) {
  throw RunFileError("diagnosis of rig kind 'pneumatic_rotary' is not implemented yet");
}

}  // namespace rigctl::diag
