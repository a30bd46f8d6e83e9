// The matrix of frequency responses of a rig with several drives, from one
// record in which every drive is excited at once by signals uncorrelated
// between drives (multisines of independent random phases, or periodic
// random): the H1 estimate per line, H = S_yx S_xx^-1 (n_y x n_x), over the
// Welch averages, with
//  * each response's multiple coherence: the part of its power the drives
//    explain together (1: linear and noise-free; low: noise, nonlinearity,
//    or an input that was not measured), and
//  * each drive's partial coherence with each response, conditioned on the
//    other drives: what that drive explains that the others do not. It
//    falls when two drives are correlated (the record cannot tell which of
//    them moved the response), which is why the drives must be uncorrelated;
//  * the condition number of S_xx per line, the same warning as a number.
// SI units; the spectra are those of tools/identify/welch.hpp.
#pragma once

#include <span>
#include <vector>

#include <Eigen/Core>

#include "tools/identify/welch.hpp"

namespace rigctl {

struct MimoFrf {
  std::vector<double> frequency_hz;
  std::vector<Eigen::MatrixXcd> value;           // per line, n_y x n_x [response unit / drive unit]
  std::vector<Eigen::VectorXd> multiple_coherence;  // per line, n_y
  std::vector<Eigen::MatrixXd> partial_coherence;   // per line, n_y x n_x
  std::vector<double> input_condition;           // per line, cond(S_xx)
  int averages = 0;
};

// drives: n_x records, responses: n_y records, all of one length. Lines in
// [band_min_hz, band_max_hz]; with `lines` given (bin indices of the
// segment, e.g. a multisine's excited lines) only those. Throws
// std::invalid_argument for no drive or response, or no line in the band.
MimoFrf estimate_mimo_frf(const std::vector<std::span<const double>>& drives,
                          const std::vector<std::span<const double>>& responses, const WelchSettings& settings,
                          double band_min_hz, double band_max_hz, const std::vector<std::size_t>& lines = {});

}  // namespace rigctl
