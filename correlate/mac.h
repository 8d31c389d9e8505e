// Modal Assurance Criterion and one-to-one pairing of measured and model modes.
//
// For a measured shape x (complex operating shape at the sensors, any scaling) and a model
// shape y (real, sampled at the same sensors with the sensor signs applied):
//
//     MAC(x, y) = |x^H y|^2 / ((x^H x) (y^H y)),     0 <= MAC <= 1,
//
// invariant to the scaling (and phase) of either shape. MAC = 1 for collinear shapes. A sensor
// without a measured entry for a mode (its entry exactly zero) is left out of that mode's MACs.
// A MAC matrix holds MAC(measured_i, model_j) at (i, j).
//
// Pairing: greedy one-to-one assignment on the MAC matrix (largest entry first, then its
// row and column are removed), keeping only pairs with MAC >= threshold. Measured or model
// modes left without a partner are reported as unpaired. Greedy assignment is exact for the
// well-separated MAC matrices that updating meets (one dominant entry per row).
// With few sensors MAC alone is not enough (distinct model modes look alike at the sensors,
// and a mode with no motion at the sensors has no MAC at all, a 0/0): pair_by_rules() also
// gates by frequency, never pairs an invisible mode, and says when it cannot decide. The
// updating then follows each pair by its full shape (mode_tracking.h), not by MAC again.
//
// Realising a complex shape x = a + i b (a test-modal tool's residue or mode shape): the real
// shape nearest it is Re(x e^{-i theta}) with theta the phase that maximises its norm, the
// principal direction of the points x_k in the complex plane. With the 2x2 matrix
// [a.a, a.b; a.b, b.b] of eigenvalues l1 >= l2 >= 0, theta = arg(x^T x) / 2 (plain transpose),
// |Re(x e^{-i theta})|^2 = l1 and the imaginary part left out |Im(x e^{-i theta})|^2 = l2. The
// modal phase collinearity
//
//     MPC = |x^T x|^2 / (x^H x)^2 = ((l1 - l2) / (l1 + l2))^2,     0 <= MPC <= 1,
//
// is 1 for a real shape times any e^{i phi} (a real normal mode) and 0 for points spread evenly
// round the origin (x = (1, i)); for two equal entries phi apart it is cos^2 phi. It is taken
// about the origin (not about the points' mean, as some tools do): a real shape's points lie on
// a line through the origin.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace jointlab::correlate {

/// MAC of a complex measured shape and a real model shape of the same length, over the sensors
/// with a measured entry (exactly zero: none); 0 if either is zero there.
double mac(const Eigen::Ref<const Eigen::VectorXcd>& measured,
           const Eigen::Ref<const Eigen::VectorXd>& model);

/// MAC of two real shapes of the same length; 0 if either is zero.
double mac(const Eigen::Ref<const Eigen::VectorXd>& a, const Eigen::Ref<const Eigen::VectorXd>& b);

/// MAC(measured.col(i), model.col(j)) at (i, j); both have one row per sensor.
Eigen::MatrixXd mac_matrix(const Eigen::Ref<const Eigen::MatrixXcd>& measured,
                           const Eigen::Ref<const Eigen::MatrixXd>& model);

/// A complex shape as the real shape nearest it (realise()).
struct RealisedShape {
  Eigen::VectorXd shape;       ///< Re(x e^{-i theta}), the sign making its largest entry positive
  double phase = 0;            ///< theta [rad]
  double mpc = 1;              ///< modal phase collinearity |x^T x|^2 / (x^H x)^2 (1 for x = 0)
  double imaginary_share = 0;  ///< |Im(x e^{-i theta})|^2 / |x|^2 = l2 / (l1 + l2): left out
};

/// The real shape nearest complex shape `x` and its MPC. An entry of x that is not zero stays
/// non-zero (a rotated entry exactly in quadrature becomes the smallest normal double): a zero
/// entry means "not measured" to mac().
RealisedShape realise(const Eigen::Ref<const Eigen::VectorXcd>& x);

/// One measured mode paired with one model mode.
struct ModePair {
  int measured = -1;  ///< column of the measured shapes
  int model = -1;     ///< column of the model shapes
  double mac = 0.0;   ///< their MAC
};

/// Result of pair_modes().
struct Pairing {
  std::vector<ModePair> pairs;         ///< sorted by measured index
  std::vector<int> unpaired_measured;  ///< measured columns without a partner, ascending
  std::vector<int> unpaired_model;     ///< model columns without a partner, ascending

  /// The model column paired with measured column i, or -1.
  int model_for(int measured) const;
  /// One line per pair and the unpaired modes, for reports.
  std::string report() const;
};

/// Greedy one-to-one pairing on a MAC matrix (rows measured, columns model); pairs below
/// threshold are not made.
Pairing pair_modes(const Eigen::Ref<const Eigen::MatrixXd>& mac_matrix, double threshold);

/// How pair_by_rules() decides a pair.
struct PairingRules {
  double mac_threshold = 0.6;     ///< a pair needs at least this sensor MAC
  double frequency_window = 0.5;  ///< and |f_model / f_test - 1| <= this (0: no window)
  double visibility = 1e-6;       ///< a model mode whose squared norm at the sensors is below
                                  ///< this times the largest (modes up to twice the highest
                                  ///< test frequency) is invisible: never paired by MAC
  double tie_mac = 0.05;          ///< candidates within this MAC of the best: frequency decides
};

/// A measured mode pair_by_rules() pairs only by a guess: the model columns it cannot tell
/// apart (the first is the one it paired).
struct PairingTie {
  int measured = -1;            ///< the measured mode
  std::vector<int> candidates;  ///< the model columns it cannot tell apart
};

/// The outcome of pair_by_rules(): the pairs, or why a pair cannot be decided.
struct RulePairing {
  Pairing pairing;  ///< the pairs made (MAC of each as in the sensor MAC matrix)
  /// Non-empty: which modes cannot be told apart, and why (one clause per tie, joined by "; ").
  std::string ambiguity;
  std::vector<PairingTie> ties;  ///< every measured mode paired by a guess, in pairing order
  std::vector<int> hidden;       ///< model columns invisible at the sensors
};

/// Pairs measured modes (rows of `mac`) with model modes (columns) one to one: a candidate is
/// a visible model mode within the frequency window with MAC >= threshold; the measured mode
/// with the strongest candidate is paired first, the modes without a shape after all others.
/// Candidates within tie_mac of the best are told apart by frequency (the nearest, when it is at
/// most half as far in ln f as the next); when frequency cannot tell them either, `ambiguity` and
/// `ties` say so (every such mode, not the first alone: a later tie is met only once the earlier
/// guess is made). A measured mode without a shape (`has_shape` false: none, or an entry at one
/// sensor only, where every MAC is 1) pairs with the nearest visible-or-not model frequency in the
/// window by the same rule (at most half as far in ln f as the next, else `ambiguity`).
/// `model_norm2` is each model mode's squared norm at the sensors. `test_names` names the measured
/// modes in `ambiguity` (the table's own numbers); where it is shorter, mode i is named i + 1.
RulePairing pair_by_rules(const Eigen::Ref<const Eigen::MatrixXd>& mac,
                          const Eigen::Ref<const Eigen::VectorXd>& test_frequency_hz,
                          const std::vector<bool>& has_shape,
                          const Eigen::Ref<const Eigen::VectorXd>& model_frequency_hz,
                          const Eigen::Ref<const Eigen::VectorXd>& model_norm2,
                          const PairingRules& rules,
                          const std::vector<std::string>& test_names = {});

}  // namespace jointlab::correlate
