// What a recovery file holds, as plain fixed-size data: the procedure's
// status (rt/procedure_status.hpp), the compensation of every level, the
// peak-valley reference and the rainflow residues. Copying it never
// allocates.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

#include "rt/procedure/procedure_spec.hpp"
#include "rt/procedure/rainflow.hpp"
#include "rt/procedure_status.hpp"

namespace rigctl {

inline constexpr std::size_t kMaxBlockRows = 32;       // rows of one block program
inline constexpr std::size_t kMaxRainflowChannels = 4;  // channels counted on the tick

// The peak-valley change detector's reference and run of cycles out of tolerance.
struct PeakValleyReference {
  bool taken = false;
  double peak_sum = 0.0, valley_sum = 0.0;  // while it is being taken
  int64_t taken_cycles = 0;
  double peak = 0.0, valley = 0.0;
  int64_t out_of_tolerance = 0;  // cycles in a row
};

struct RainflowResidue {
  uint32_t size = 0;
  bool has_pending = false;
  double pending = 0.0;
  int8_t direction = 0;
  std::array<double, RainflowCounter::kStackCapacity> points{};
  RainflowMatrixData committed;  // the cycles closed so far (bins, totals, damage)
};

// Everything a resumed test needs to continue where it was.
struct ProcedureRecovery {
  uint64_t sequence = 0;  // written in this order; a reader keeps the newest
  ProcedureStatus status;
  std::array<double, kMaxBlockRows> peak_command{};    // peak_valley: each row's commanded peak
  std::array<double, kMaxBlockRows> valley_command{};  // and valley
  std::array<bool, kMaxBlockRows> row_compensated{};   // a row has its own correction yet
  PeakValleyReference reference;
  uint32_t rainflow_channels = 0;
  std::array<RainflowResidue, kMaxRainflowChannels> rainflow{};
};

}  // namespace rigctl
