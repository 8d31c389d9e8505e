// The pairs a fit's result leaves to frequency alone, fitted the other way round (internal to
// update_linear()): two measured modes paired with model modes adjacent in frequency that the
// sensors cannot tell apart are paired by nearest frequency without a tie, yet a start whose
// order of the two model modes is the reverse of the truth's pairs them crosswise, and the fit
// keeps that order to its end.
#pragma once

#include <string>
#include <vector>

#include "jointlab/correlate/linear_problem.h"

namespace jointlab::correlate::detail {

/// A result's pairs with two measured modes' partners exchanged, and why it is a candidate.
struct SwappedPairs {
  TrackedPoint point;  ///< the result with the two partners exchanged
  std::string why;     ///< which two, and that the sensors cannot tell their partners apart
  /// One measured mode moved to a model mode no other is paired with (not an exchange of two):
  /// a rival only where it moves a set the frequencies see at the winner, or leaves one flat
  /// (best_start in linear_fit.cc).
  bool unpaired = false;
};

/// The pairings of `result` with the partners of two measured modes exchanged, where the two
/// are paired with model modes adjacent in frequency that the sensors cannot tell apart (no
/// shape, or both partners at or above the MAC threshold within the tie MAC of each other); and
/// with one measured mode moved to an unpaired, visible model mode beside its partner that the
/// sensors cannot tell from it (SwappedPairs::unpaired).
/// Each is a whole fit to try: a linearised refit is no guide (the two chains' crosswise
/// result, fitted the other way round, came 26 chi-square units lower where one Gauss-Newton
/// step from it foretold 7e4 higher).
std::vector<SwappedPairs> swapped_pairings(const LinearProblem& p, const TrackedPoint& result);

}  // namespace jointlab::correlate::detail
