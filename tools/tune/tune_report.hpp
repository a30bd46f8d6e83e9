// What `rigctl tune` prints and writes (--json): the gains, the predicted
// margins on the measured plant, the predicted standard step, the relay's
// result, and the tuned loop on the FRF's frequencies for the Bode plot.
#pragma once

#include <optional>
#include <ostream>
#include <string>

#include "tools/identify/frf_data.hpp"
#include "tools/tune/relay_experiment.hpp"
#include "tools/tune/tune_command.hpp"

namespace rigctl {

struct TuneReportInput {
  std::string rig;
  const TuneOptions* options = nullptr;
  const TuneResult* result = nullptr;
  const FrfData* frf = nullptr;            // when the design used one
  const RelayResult* relay = nullptr;      // --method relay
  const PlantModel* model = nullptr;       // the fitted plant of the prediction
};

void print_tune(const TuneReportInput& in, std::ostream& out);
void print_margins(const char* what, const Margins& m, std::ostream& out);
void write_tune_json(const TuneReportInput& in, const std::string& path);

}  // namespace rigctl
