// Measured and model backbones of the Iwan update: amplitude-dependent frequency and damping.
//
// Model curve: QSMA of elastic mode R (qsma.h) gives q, omega(q), zeta(q). The measuring
// sensor (dof d, sign s) sees the displacement amplitude x = |u_d|, u_d the QSMA deflection
// at d (qsma_at.h; q |phi_R[d]| only while the joints stick: in macroslip the deflected shape
// leaves the linear mode's); the amplitude of the quantity `process` reported is a = x omega^p
// (p = 0, 1, 2 for displacement, velocity, acceleration), omega the frequency the signal
// oscillates at.
// Like with like (the default, IwanComparison::kMatched): a ring-down backbone is compared
// with what a ring-down of the model shows, the first-harmonic frequency and
// D / (2 pi q dE/dq) (QSMA's ring-down columns); a stepped-sine backbone with what a steady
// state shows, the first-harmonic frequency and D / (2 pi k_1 q^2); omega above is the
// first-harmonic frequency. kSecant compares every backbone with the paper's secant pair
// sqrt(alpha/q), D / (2 pi alpha q), omega the secant frequency. The model frequency and damping
// are evaluated exactly at each measured amplitude a_j (qsma_at.h: one static solve per secant
// step, no grid), so the macroslip knee is where the model puts it.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointlab/core/units.h"
#include "jointlab/model/joint_condensation.h"

namespace jointlab::correlate {

/// The amplitude quantity of measured backbones (as `process --amplitude`).
enum class AmplitudeQuantity { kDisplacement, kVelocity, kAcceleration };

/// Power of omega that turns a modal amplitude into this quantity's (0, 1 or 2).
int amplitude_power(AmplitudeQuantity q);

/// The amplitude quantity of a motion quantity, as a process or stepped-sine folder names it
/// (data/process_folder.h); a force is no amplitude (programmer error).
AmplitudeQuantity amplitude_quantity(Quantity q);

/// How a backbone was measured, hence which model pair it is compared with.
enum class BackboneKind {
  kRingdown,    ///< free decay (`process`): first-harmonic frequency, ring-down damping
  kSteppedSine  ///< one steady state per level (`stepped-sine`): first-harmonic pair
};

/// Which model columns measured backbones are compared with.
enum class IwanComparison {
  kMatched,  ///< each backbone with the pair of its kind (ring-down or first-harmonic)
  kSecant    ///< every backbone with QSMA's secant pair sqrt(alpha/q), D/(2 pi alpha q)
};

/// One measured backbone curve: points of one channel (or pooled hits of it).
struct MeasuredBackbone {
  BackboneKind kind = BackboneKind::kRingdown;  ///< how it was measured
  int sensor = 0;  ///< index into the sensors: where the amplitude is measured
  /// True: `amplitude` is the QSMA modal amplitude q of the target's mode (mass-normalised
  /// shape; no sensor, `sensor` unused, the amplitude quantity of the options does not apply).
  bool modal = false;
  std::string source;                ///< where it was read (file), for messages; may be empty
  Eigen::VectorXd amplitude;         ///< amplitude a_j (SI units of the quantity), > 0
  Eigen::VectorXd frequency_hz;      ///< f_j [Hz]
  Eigen::VectorXd damping_ratio;     ///< zeta_j
  Eigen::VectorXd frequency_std_hz;  ///< k sigma_f,j [Hz] as read (0: the floor)
  Eigen::VectorXd damping_std;       ///< k sigma_z,j as read (0: the floor)
  /// k of the two std columns: `process` and `stepped-sine` write expanded uncertainties
  /// (k = 3 by default, their `coverage_factor`); the objective weighs each point by std / k.
  double coverage_factor = 1.0;
};

/// The measured data of one model mode.
struct IwanTarget {
  int mode = 1;                          ///< elastic model mode R (1-based, as `modes`)
  std::vector<MeasuredBackbone> curves;  ///< its measured backbones
  double linear_frequency_hz = 0;        ///< measured linear frequency (0: unknown)
};

/// A model's backbone as a measured one of `kind` would show it (the ring-down or steady-state
/// pair; with IwanComparison::kSecant the secant pair), in the measured amplitude a =
/// |u_d| omega^power (u_d the QSMA deflection at the measuring DOF; q and power 0 for the
/// modal amplitude), at `points` amplitudes log-spaced over [a_lo, a_hi]; the model's own damping
/// (JointCondensation::linear_damping) included.
struct ModelBackbone {
  Eigen::VectorXd amplitude;      ///< a [SI of the measured amplitude]
  Eigen::VectorXd frequency_hz;   ///< f [Hz]
  Eigen::VectorXd damping_ratio;  ///< zeta
  bool clipped = false;  ///< true: the model does not reach the top of the range (no static
                         ///< solution past its largest load) or fails below it; the curve stops
};

/// model_backbone() of elastic mode `mode` (1-based), its amplitude the modal amplitude q
/// (no dof) or the QSMA deflection at matrix DOF `dof` times omega^power (qsma_at.h, as
/// update-iwan fits it); InputError if there is no such mode or it leaves `dof` still.
ModelBackbone model_backbone(const model::JointCondensation& model, int mode,
                             std::optional<Eigen::Index> dof, int power, BackboneKind kind,
                             IwanComparison comparison, double a_lo, double a_hi, int points);

}  // namespace jointlab::correlate
