// The settings of the Iwan update (update_iwan(), iwan_update.h): the search box of
// p = (F_S [N], gamma, chi, beta), K_T = gamma K_s, and the optimiser.
//
// Optimisers, on one interface and one budget of QSMA evaluations:
//   kPaper       the paper's Monte Carlo: `samples` uniform samples in the bounds, keep the
//                best, contract the bounds to +-contraction around it, repeat until a round
//                brings no improvement or the budget is spent;
//   kPaperLog    the same with F_S, gamma and beta sampled logarithmically;
//   kGlobalLocal logarithmic sampling with half the budget, then Ceres (central differences on
//                ln F_S, ln gamma, chi, ln beta) from the best `local_starts` samples.
#pragma once

#include <functional>
#include <optional>
#include <string>

#include "jointlab/correlate/iwan_backbone.h"
#include "jointlab/model/iwan.h"

namespace jointlab::correlate {

/// Bounds of the Iwan parameters (F_S, gamma and beta > 0; -1 < chi).
struct IwanBounds {
  double Fs_min = 1, Fs_max = 1e3;         ///< [N]
  double gamma_min = 0.3, gamma_max = 3;   ///< K_T / K_s
  double chi_min = -0.95, chi_max = 0;     ///< exponent
  double beta_min = 0.01, beta_max = 100;  ///< macroslip weight
};

/// The default search box of `update-iwan` and `run`: F_S within a factor 30 of the start's,
/// gamma 0.05-2, chi -0.95-0 (widened to hold a start outside it), beta 0.01-100.
IwanBounds default_iwan_bounds(const model::IwanParameters& start);

/// Which optimiser update_iwan() runs.
enum class IwanOptimizer { kPaper, kPaperLog, kGlobalLocal };

/// Settings of update_iwan().
struct IwanUpdateOptions {
  IwanOptimizer optimizer = IwanOptimizer::kGlobalLocal;  ///< method
  IwanBounds bounds;                                      ///< search box
  double fixed_gamma = 0;                                 ///< > 0: gamma held at this value
  std::optional<double> fixed_beta;  ///< beta held at this value (>= 0; 0: no macroslip weight)
  AmplitudeQuantity amplitude = AmplitudeQuantity::kVelocity;  ///< measured amplitude quantity
  IwanComparison comparison = IwanComparison::kMatched;        ///< model columns compared
  int samples = 100;                                           ///< samples per Monte Carlo round
  double contraction = 0.03;      ///< Monte Carlo: bounds contract to +-this around the best
  int max_evaluations = 1500;     ///< budget of QSMA evaluations
  int local_starts = 3;           ///< global-local: Ceres starts from the best samples
  double frequency_floor = 1e-4;  ///< sigma_f at least this times f
  double damping_floor = 0.02;    ///< sigma_z at least this times zeta
  unsigned seed = 1;              ///< random seed
  /// Threads evaluating the samples of a round (0: every core); the result does not depend
  /// on it.
  int threads = 0;
  /// Called after every evaluation with (evaluations, best cost so far).
  std::function<void(int, double)> progress;
  /// The structure's own damping (Model::modal_ratio Z, added to every model damping):
  /// false holds the model's; true identifies it with the Iwan parameters, in
  /// [0, linear_damping_max]. Damping residuals are linear in Z, so at any Iwan parameters the
  /// best Z is the weighted mean of the measured damping minus the joints' (clamped to its
  /// range): every candidate is scored at its own best Z (variable projection).
  bool fit_linear_damping = false;
  double linear_damping_max = 0.05;  ///< upper bound of a fitted Z
  /// True when the model's linear part was fitted to measured linear frequencies before this
  /// update (the campaign's linear step): the report states the linear part's systematic effect
  /// on the parameters (IwanUpdateSummary::linear_part_sensitivity) without sending to
  /// update-linear.
  bool linear_part_updated = false;
  /// What is wrong with these options, or "".
  std::string error() const;
};

}  // namespace jointlab::correlate
