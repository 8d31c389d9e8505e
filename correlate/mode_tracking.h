// Following model modes by their full shape as the stiffness moves.
//
// With few sensors, distinct model modes look alike at the sensors, so pairing by the sensor
// MAC alone can jump from one model mode to another as the joint stiffness changes. The full
// shapes can always tell them apart: for mass-normalised shapes (phi^T M phi = 1) the
// mass-weighted MAC of a shape a before and b after a small change of K is
//     MAC_M(a, b) = (a^T M b)^2,      0 <= MAC_M <= 1,
// 1 for the same shape, and the MAC_M of a with all the new shapes sums to at most 1.
// A tracked mode is followed to the new mode with the largest MAC_M when that is at least
// min_mac and no other new mode comes within `margin` of it; otherwise the step is halved
// (the path K(s), s from 0 to 1, is walked in smaller steps) until it is, or the mode is
// lost. Walking in steps that small follows each mode along its continuous branch, through
// crossings (where two modes exchange order but keep their shapes) and veerings alike.
#pragma once

#include <functional>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace jointlab::correlate {

/// The elastic modes of K phi = omega^2 M phi, mass-normalised, ascending.
struct ElasticModes {
  Eigen::VectorXd frequency_hz;  ///< f_j [Hz], one per elastic mode
  Eigen::MatrixXd shapes;        ///< phi_j as columns, phi^T M phi = 1
};

/// The elastic modes of (M, K); InputError when K is indefinite.
ElasticModes elastic_modes(const Eigen::SparseMatrix<double>& mass,
                           const Eigen::SparseMatrix<double>& stiffness);

/// Settings of follow_modes() and follow_path().
struct TrackingOptions {
  double min_mac = 0.8;   ///< MAC_M with the previous step at least this
  double margin = 0.3;    ///< and at least this above any other new mode's
  int substeps = 1;       ///< follow_path(): walk the path in at least this many equal steps
  int max_halvings = 10;  ///< a step is halved at most this many times before a mode is lost
  /// follow_path(): called before each eigen-solve; it may throw to stop the work (Ctrl-C)
  std::function<void()> interrupt;
};

/// For each entry of `tracked` (a column of `before`, or -1), the column of `after` it
/// continues as, or -1 when it cannot be told (MAC_M below min_mac, or another within margin).
/// `mac` (optional) receives each tracked mode's best MAC_M.
std::vector<int> follow_modes(const Eigen::Ref<const Eigen::MatrixXd>& before,
                              const Eigen::Ref<const Eigen::MatrixXd>& after,
                              const Eigen::SparseMatrix<double>& mass,
                              const std::vector<int>& tracked, const TrackingOptions& options,
                              std::vector<double>* mac = nullptr);

/// Modes at the end of a path and where the tracked ones went.
struct FollowedModes {
  ElasticModes modes;        ///< the elastic modes at s = 1
  std::vector<int> columns;  ///< the column each tracked mode continues as (-1: was -1)
  int solves = 0;            ///< eigen-solves used
};

/// Follows the tracked columns of `start` (the modes at s = 0) along K(s) to s = 1;
/// std::nullopt when a tracked mode is lost (see TrackingOptions).
std::optional<FollowedModes> follow_path(
    const std::function<Eigen::SparseMatrix<double>(double)>& stiffness,
    const Eigen::SparseMatrix<double>& mass, const ElasticModes& start,
    const std::vector<int>& tracked, const TrackingOptions& options);

/// Whether two pairings pair every measured mode with the same model mode: `columns_a[i]`, a
/// mode of `a` (or -1: unpaired), and `columns_b[i]` of `b`, modes of one mass matrix at two
/// stiffnesses. The same ones unpaired, and each pair's shape with MAC_M at least `min_mac`
/// with the other's partner and the modes within a relative `cluster` of its frequency (modes
/// that close are one eigenspace to the data: their shapes mix arbitrarily from one stiffness to
/// the next, the example beam's 747.94 and 747.97 Hz pair), both ways. Mode numbers alone cannot
/// say it: a mode crossing or veering between the two points renumbers the modes (the beam's
/// sixth bending mode is model mode 9 with spring.rz at 1e5 and model mode 10 with rz at 0.1,
/// the twisting mode having passed it).
bool same_partners(const Eigen::SparseMatrix<double>& mass, const ElasticModes& a,
                   const std::vector<int>& columns_a, const ElasticModes& b,
                   const std::vector<int>& columns_b, double min_mac = 0.5, double cluster = 1e-3);

}  // namespace jointlab::correlate
