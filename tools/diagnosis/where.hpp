// "Where before what" (docs/diagnosis.md 3): before any candidate is
// compared, the engine asks at which place of the model (a force on a body,
// a flow into a chamber, an error on a sensor: RigModel::places) a missing
// signal explains the calibrated baseline's residual, and which measured
// features that signal follows.
//
// The missing signal d(t) at a place is reconstructed by the model's own
// inverse, linearised about the calibrated replay and restricted to a small
// library of features phi_k of the measured record (sign and value of each
// velocity, pressures and their difference, the command near null, travel
// since reversal, rates; a constant; for a sensor its own rate, value and
// a drift): the response of every output to each phi_k added at the place
// is one replay each (a forward difference), so the residual r ~ sum c_k
// G phi_k is a linear regression, solved sparsely (orthogonal matching
// pursuit, a regressor kept only while it lowers the BIC at N_eff) on the
// estimation part and scored on the held-out part. Internal to the diagnosis.
#pragma once

#include <string>
#include <vector>

#include "tools/diagnosis/where_result.hpp"
#include "tools/diagnosis/workspace.hpp"

namespace rigctl::diag {

// A place is a "where" when its signal explains at least this share of the
// held-out residual above the noise floor, and the baseline misfits beyond
// the noise (criteria.hpp misfits_beyond_noise) on some output. A quarter: a
// missing signal that takes less is not the misfit's main part.
constexpr double kWhereMinShare = 0.25;
// Regressors per place: a friction's sign and viscous parts and a level
// (a sensor's rate, value and offset) are three.
constexpr std::size_t kWhereMaxRegressors = 3;

// The where of the model `s` (the calibrated baseline) on w's record.
WhereResult locate(const Workspace& w, const Scored& s);

// Whether `cause` enters at one of the places that explain about as much
// as the best one (at least 0.8 of its share): the candidate's place agrees
// with where the misfit is. True when nothing significant was found.
bool where_agrees(const WhereResult& where, const std::string& cause);

// The causes that enter at the best place, or none when it is not significant.
std::vector<std::string> where_causes(const WhereResult& where);

// Where before what, cautiously: when none of the `top` best-screened
// candidates (`screened`, their causes best first) enters at the best place,
// the index of the best-screened one that does, to be refitted as well; it
// only adds a refit, never takes one away, and the gates still decide.
// screened.size() when there is none to add.
std::size_t where_promotion(const WhereResult& where, const std::vector<std::string>& screened, std::size_t top);

}  // namespace rigctl::diag
