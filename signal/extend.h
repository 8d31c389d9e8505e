// Extension of a record beyond its ends by linear prediction.
//
// A ring-down is a sum of damped sinusoids, which an autoregressive model
//   x[k] = sum_{j=1}^{p} c_j x[k - j]      (forward),
//   x[k] = sum_{j=1}^{p} d_j x[k + j]      (backward)
// continues exactly (p >= twice the number of modes). Band-pass filters smear an
// abrupt start or end of a record over their settling time; continuing the record
// smoothly across its ends moves that transient outside the data. The
// coefficients are least-squares fits (covariance method) over `fit_length`
// samples next to the end being continued. With lag L > 1 each sample is
// predicted from samples L apart (x[k] from x[k - L], ..., x[k - pL]): for a
// record sampled far above its content (low-passed) this is the recursion of
// the decimated record, far better conditioned than lag 1.
#pragma once

#include <Eigen/Core>

namespace jointlab::signal {

/// What extend_record produced.
struct Extension {
  Eigen::VectorXd samples;        ///< before + original + after
  Eigen::Index before = 0;        ///< samples prepended
  Eigen::Index after = 0;         ///< samples appended
  Eigen::Index before_valid = 0;  ///< prepended samples that are a faithful continuation
  Eigen::Index after_valid = 0;   ///< appended samples that are a faithful continuation
};

/// The continuations alone, without a copy of x (for records too long to copy).
struct Continuation {
  Eigen::VectorXd before;         ///< the samples before x[0], in time order
  Eigen::VectorXd after;          ///< the samples after x[n-1]
  Eigen::Index before_valid = 0;  ///< faithful samples of `before` (those next to x)
  Eigen::Index after_valid = 0;   ///< faithful samples of `after` (those next to x)
};

/// What extend_record puts before and after x (the same numbers).
Continuation continue_record(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Index before,
                             Eigen::Index after, int order, Eigen::Index fit_length,
                             double max_growth = 20.0, Eigen::Index lag = 1);

/// Continues x by `before` samples at its start and `after` at its end with AR
/// models of `order` and sample spacing `lag` fitted over `fit_length` samples at
/// each end. Where an extension grows beyond `max_growth` times the RMS of the
/// samples it was fitted on (peak over RMS sqrt 2) it is judged unstable from there
/// on: the faithful first half of what came before is kept, the second half faded
/// out by a half cosine, and the rest is zeros (before_valid / after_valid say how
/// much is faithful).
Extension extend_record(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Index before,
                        Eigen::Index after, int order, Eigen::Index fit_length,
                        double max_growth = 20.0, Eigen::Index lag = 1);

}  // namespace jointlab::signal
