#include "config/controller_kind.hpp"

#include "config/config_reader.hpp"

namespace rigctl {

std::vector<ControllerKind> controllers_of(RigKind rig) {
  std::vector<ControllerKind> out;
  for (const ControllerKind k : KindNames<ControllerKind>::known) {
    if (rig_of(k) == rig) out.push_back(k);
  }
  return out;
}

ControllerKind read_controller_kind(ConfigReader& r, const std::string& key, RigKind rig) {
  const auto kind = r.kind<ControllerKind>(key);
  if (rig_of(kind) != rig) {
    std::string own;
    for (const ControllerKind k : controllers_of(rig)) own += (own.empty() ? "" : ", ") + std::string(to_string(k));
    r.fail(key, "controller '" + std::string(to_string(kind)) + "' is for the " + std::string(to_string(rig_of(kind))) +
                    " rig, not " + std::string(to_string(rig)) + " (" + std::string(to_string(rig)) + " runs: " + own +
                    ")");
  }
  return kind;
}

}  // namespace rigctl
