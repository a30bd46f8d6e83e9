#include "tools/common/stage_text.hpp"

#include <iomanip>
#include <sstream>

namespace rigctl {

std::string describe_stages(const StageDurations& ns) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(1);
  for (std::size_t i = 0; i < kTickStageCount; ++i) {
    os << (i > 0 ? ", " : "") << to_string(static_cast<TickStage>(i)) << " " << static_cast<double>(ns[i]) / 1e3;
  }
  os << " us";
  return os.str();
}

}  // namespace rigctl
