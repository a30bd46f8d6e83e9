#include "tools/iterate/mimo_iteration.hpp"

#include <cmath>
#include <stdexcept>

#include "tools/iterate/spectrum.hpp"

namespace rigctl {

namespace {

Records minus(const Records& a, const Records& b) {
  Records out = a;
  for (std::size_t c = 0; c < a.size(); ++c) {
    for (std::size_t i = 0; i < a[c].size(); ++i) out[c][i] -= b[c][i];
  }
  return out;
}

void add_to(Records& a, const Records& b) {
  for (std::size_t c = 0; c < a.size(); ++c) {
    for (std::size_t i = 0; i < a[c].size(); ++i) a[c][i] += b[c][i];
  }
}

void check_shapes(const MimoDriveInverse& inverse, const Records& targets) {
  if (targets.size() != inverse.responses()) throw std::invalid_argument("mimo iteration: one target per response channel is needed");
  for (const auto& t : targets) {
    if (t.size() != targets.front().size()) throw std::invalid_argument("mimo iteration: targets of different lengths");
  }
}

// Halves gain(b, j) where channel j's error energy in band b grew.
void adapt_gain(const Eigen::MatrixXd& before, const Eigen::MatrixXd& now, Eigen::MatrixXd& gain) {
  for (Eigen::Index b = 0; b < gain.rows(); ++b) {
    for (Eigen::Index j = 0; j < gain.cols(); ++j) {
      if (now(b, j) > before(b, j)) gain(b, j) *= 0.5;
    }
  }
}

}  // namespace

double band_relative_rms(const std::vector<double>& target, const std::vector<double>& response, double period_s,
                         double low_hz, double high_hz) {
  std::vector<double> error(target.size());
  for (std::size_t i = 0; i < target.size(); ++i) error[i] = target[i] - response[i];
  const auto e = band_limited(error, period_s, low_hz, high_hz);
  const auto t = band_limited(target, period_s, low_hz, high_hz);
  double ee = 0.0, tt = 0.0;
  for (std::size_t i = 0; i < e.size(); ++i) {
    ee += e[i] * e[i];
    tt += t[i] * t[i];
  }
  return tt > 0.0 ? std::sqrt(ee / tt) : INFINITY;
}

MimoIterationResult iterate_mimo(const MimoDriveInverse& inverse, const Records& targets, const PlayDrives& play,
                                 const MimoIterationSettings& s, const MimoIterationHooks& hooks) {
  check_shapes(inverse, targets);
  const auto& bands = inverse.bands();
  const double low = bands.edges_hz[1], high = bands.edges_hz.back();
  Eigen::MatrixXd gain = Eigen::MatrixXd::Constant(static_cast<Eigen::Index>(bands.size()),
                                                   static_cast<Eigen::Index>(targets.size()), s.first_level);
  MimoIterationResult result;
  result.drives = inverse.apply(targets, gain);
  gain.setOnes();
  Eigen::MatrixXd previous_energy;
  for (int it = 0; it < s.max_iterations; ++it) {
    if (hooks.admit) {
      const std::string why = hooks.admit(result.drives, it + 1);
      if (!why.empty()) {
        result.stopped = "drive " + std::to_string(it + 1) + " not played: " + why;
        break;
      }
    }
    Records played = play(result.drives);
    if (played.empty()) {
      result.stopped = "drive " + std::to_string(it + 1) + "'s run did not complete";
      break;
    }
    result.responses = std::move(played);
    const Records error = minus(targets, result.responses);
    std::vector<double> rms;
    for (std::size_t j = 0; j < targets.size(); ++j) {
      rms.push_back(band_relative_rms(targets[j], result.responses[j], s.period_s, low, high));
    }
    result.error.push_back(rms);
    if (hooks.on_iteration) hooks.on_iteration(it + 1, result.drives, result.responses, rms);
    bool within = true;
    for (double r : rms) within = within && r <= s.tolerance;
    if (within) {
      result.converged = true;
      break;
    }
    if (it + 1 == s.max_iterations) break;  // the drives returned are the ones played
    const Eigen::MatrixXd energy = inverse.band_energy(error);
    if (previous_energy.size() > 0) adapt_gain(previous_energy, energy, gain);
    previous_energy = energy;
    add_to(result.drives, inverse.apply(error, gain));
  }
  return result;
}

MimoFrf diagonal_only(const MimoFrf& frf) {
  MimoFrf out = frf;
  for (auto& h : out.value) {
    if (h.rows() != h.cols()) throw std::invalid_argument("diagonal_only: a square FRF is needed");
    h = Eigen::MatrixXcd(h.diagonal().asDiagonal());
  }
  return out;
}

}  // namespace rigctl
