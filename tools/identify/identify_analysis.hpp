// From the identification run's record to the FRF: where the excitation is
// in the log, which whole segments are analysed (the first one, while the
// loop settles into the excitation, is not), the operating point as the rig
// held it, and the estimate itself (tools/identify/frf_estimate.hpp).
#pragma once

#include <cstddef>
#include <vector>

#include "tools/identify/excitation.hpp"
#include "tools/identify/frf_data.hpp"
#include "tools/identify/identify_plan.hpp"
#include "tools/runfile/run_file.hpp"

namespace rigctl {

// Index of the excitation's first tick in the logged demand: the end of the
// settling hold (the demand exactly at the operating point), aligned on the
// table's first non-zero value. Throws std::runtime_error when the log has
// no such hold followed by the whole excitation.
std::size_t find_excitation_start(const std::vector<double>& demand, double operating_point,
                                  const std::vector<double>& excitation, std::size_t settle_ticks);

// The FRF of the run: channels named from the plan, the demand, command and
// responses read from `run` by their run-file names.
FrfData analyse_identification(const RunFile& run, const IdentifyPlan& plan, const Excitation& excitation,
                               const FrfChannel& demand, const FrfChannel& command,
                               const std::vector<FrfChannel>& responses);

}  // namespace rigctl
