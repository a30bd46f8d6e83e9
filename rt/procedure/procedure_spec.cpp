#include "rt/procedure/procedure_spec.hpp"

namespace rigctl {

int64_t ProcedureSpec::programmed_cycles() const {
  // Walks the flat list with the repeat groups' multipliers.
  int64_t total = 0;
  std::vector<int64_t> factor{1};
  for (const auto& s : steps) {
    switch (s.kind) {
      case StepKind::kRepeatBegin: factor.push_back(factor.back() * s.repeats); break;
      case StepKind::kRepeatEnd: factor.pop_back(); break;
      case StepKind::kSine: total += factor.back() * s.rows[0].cycles; break;
      case StepKind::kBlocks: {
        int64_t per_pass = 0;
        for (const auto& r : s.rows) per_pass += r.cycles;
        total += factor.back() * per_pass * s.repeats;
        break;
      }
      case StepKind::kDrive: total += factor.back() * s.repeats; break;
      default: break;
    }
  }
  return total;
}

}  // namespace rigctl
