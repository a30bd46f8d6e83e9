#include "config/controller_kind.hpp"

#include "config/config_reader.hpp"

namespace rigctl {

bool runs_on(ControllerKind k, RigKind rig) {
  // The two-poster's posts are position loops like the quarter car's and the
  // pneumatic servo's: each post runs either of their controllers.
  if (rig == RigKind::kTwoPoster) return k == ControllerKind::kPi || k == ControllerKind::kPvp;
  return rig_of(k) == rig;
}

std::vector<ControllerKind> controllers_of(RigKind rig) {
  std::vector<ControllerKind> out;
  for (const ControllerKind k : KindNames<ControllerKind>::known) {
    if (runs_on(k, rig)) out.push_back(k);
  }
  return out;
}

ControllerKind read_controller_kind(ConfigReader& r, const std::string& key, RigKind rig) {
  const auto kind = r.kind<ControllerKind>(key);
  if (!runs_on(kind, rig)) {
    std::string own;
    for (const ControllerKind k : controllers_of(rig)) own += (own.empty() ? "" : ", ") + std::string(to_string(k));
    r.fail(key, "controller '" + std::string(to_string(kind)) + "' is for the " + std::string(to_string(rig_of(kind))) +
                    " rig, not " + std::string(to_string(rig)) + " (" + std::string(to_string(rig)) + " runs: " + own +
                    ")");
  }
  return kind;
}

}  // namespace rigctl
