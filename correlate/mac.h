// Modal Assurance Criterion and one-to-one pairing of measured and model modes.
//
// For a measured shape x (complex operating shape at the sensors, any scaling) and a model
// shape y (real, sampled at the same sensors with the sensor signs applied):
//
//     MAC(x, y) = |x^H y|^2 / ((x^H x) (y^H y)),     0 <= MAC <= 1,
//
// invariant to the scaling (and phase) of either shape. MAC = 1 for collinear shapes.
// A MAC matrix holds MAC(measured_i, model_j) at (i, j).
//
// Pairing: greedy one-to-one assignment on the MAC matrix (largest entry first, then its
// row and column are removed), keeping only pairs with MAC >= threshold. Measured or model
// modes left without a partner are reported as unpaired. Greedy assignment is exact for the
// well-separated MAC matrices that updating meets (one dominant entry per row); it is
// recomputed at every optimiser evaluation so that modes that swap order stay paired by shape.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace jointlab::correlate {

/// MAC of a complex measured shape and a real model shape of the same length; 0 if either is zero.
double mac(const Eigen::Ref<const Eigen::VectorXcd>& measured,
           const Eigen::Ref<const Eigen::VectorXd>& model);

/// MAC of two real shapes of the same length; 0 if either is zero.
double mac(const Eigen::Ref<const Eigen::VectorXd>& a, const Eigen::Ref<const Eigen::VectorXd>& b);

/// MAC(measured.col(i), model.col(j)) at (i, j); both have one row per sensor.
Eigen::MatrixXd mac_matrix(const Eigen::Ref<const Eigen::MatrixXcd>& measured,
                           const Eigen::Ref<const Eigen::MatrixXd>& model);

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

}  // namespace jointlab::correlate
