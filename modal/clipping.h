// Samples pinned at a channel's extreme value: a sensor or recorder driven past its range.
//
// An overloaded channel holds its full-scale value while the structure's response is larger:
// the first cycles of a hard hit are cut flat, and whatever is read from them (through any
// band) is the clipping's, not the structure's. The recorder writes the same number for every
// such sample, so a clipped channel reaches its largest (or smallest) value at several
// samples in several separate runs, one run per clipped peak. A ring-down that is not
// clipped reaches its extreme once: at its first peak, where successive samples differ unless
// the recorder's step is coarse, and the next peak is lower by the decay of a cycle.
// Required of each side (largest, smallest) apart: at least kMinClippedSamples samples at
// that exact value in at least kMinClippedRuns runs, each flat over kMinClippedRunSamples or
// more consecutive samples. (A single run, however long, is a peak sampled finely by a coarse
// recorder, or one clipped peak that did not ring on: no ring-down point depends on it alone.
// A sine of constant amplitude, or one barely damped, written with a few digits, reaches its
// largest value at many peaks, but at one sample each, or two where the peak falls midway
// between them: a cut peak is flat where a sine's is curved.)
#pragma once

#include <Eigen/Core>

namespace jointlab::modal {

/// Samples at an extreme value required to call a side of a channel clipped.
inline constexpr Eigen::Index kMinClippedSamples = 3;
/// Separate runs of such samples required (one per clipped peak).
inline constexpr Eigen::Index kMinClippedRuns = 2;
/// Consecutive samples at the value that make a run flat (a cut peak, not a sine's).
inline constexpr Eigen::Index kMinClippedRunSamples = 3;

/// Where a channel is clipped: its samples at a pinned extreme value and the last of them.
struct Clipping {
  Eigen::Index samples = 0;  ///< samples at a pinned extreme value (both sides together)
  Eigen::Index last = -1;    ///< index of the last of them (-1: none)
  bool high_pinned = false;  ///< the largest value is pinned
  bool low_pinned = false;   ///< the smallest value is pinned
  double high = 0.0;         ///< the channel's largest value
  double low = 0.0;          ///< the channel's smallest value
  /// True when some side of the channel is clipped.
  bool found() const { return samples > 0; }
};

/// The samples of `x` pinned at its largest or smallest value (see the file comment).
Clipping find_clipping(const Eigen::Ref<const Eigen::VectorXd>& x);

}  // namespace jointlab::modal
