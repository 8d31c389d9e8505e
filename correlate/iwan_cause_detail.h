// What the Iwan update's cause line and report share (internal): the tests of the fitted curve's
// linear limit against the measured low-amplitude frequency (MisfitEvidence).
#pragma once

#include <string>

#include "jointlab/correlate/iwan_update.h"

namespace jointlab::correlate::iwan_detail {

/// The model as given (K_T = K_s, gamma 1: the stiffness update-linear fits to the measured linear
/// frequencies) has mode R at the measured low-amplitude frequency.
bool model_as_given_matches(const MisfitEvidence& e);

/// K_T ended at a bound short of the measured low-amplitude frequency: the linear limit misses it
/// on the side the bound kept K_T from (below the data at the upper bound, above at the lower).
bool kt_stopped_short(const IwanUpdateSummary& s);

/// F_S free at its upper bound and the fitted joint still slipping at the lowest measured
/// amplitudes, where the data lie above it: amplitudes larger than the quantity they are read as.
bool amplitudes_read_too_large(const IwanUpdateSummary& s);

/// F_S free at its lower bound and the fitted curve above the data at the highest measured
/// amplitudes, the data falling more over them than it: amplitudes smaller than they are read as.
bool amplitudes_read_too_small(const IwanUpdateSummary& s);

/// The words by which the cause line names, beside a damping column in another unit, a joint of
/// chi above chi's upper bound (the low end's damping rising more steeply than chi up to it gives).
inline constexpr const char* kLargerChiWords = ", or a joint of chi above its upper bound";

}  // namespace jointlab::correlate::iwan_detail
