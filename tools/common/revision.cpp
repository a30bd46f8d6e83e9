#include "tools/common/revision.hpp"

namespace rigctl {

const char* rigctl_revision() {
  return
#include "rigctl_revision.inc"
      ;
}

}  // namespace rigctl
