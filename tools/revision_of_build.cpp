// rigctl's git revision as this build saw it (tools/common/revision.hpp),
// from the file the rigctl_revision target rewrites when it changes.
#include "tools/common/revision.hpp"

namespace rigctl {

const char* rigctl_revision() {
  return
#include "rigctl_revision.inc"
      ;
}

}  // namespace rigctl
