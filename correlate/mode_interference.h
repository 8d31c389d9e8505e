// Other modes' share of the joint slip along a measured backbone.
//
// QSMA describes one mode alone moving the joints. Just after an impact several
// modes ring at once; while a higher mode still slips the rivets, the damping
// measured for a lower one includes that slip's dissipation, which no
// single-mode curve can fit. For a point of mode k's backbone at time t, with
// u_j the joints' slip per unit modal amplitude of mode j (|phi_j(a) - phi_j(b)|
// over the Iwan joints) and q_j(t) each measured mode's modal amplitude then,
//   share_k(t) = sum_i u_k,i sum_{j != k} u_j,i q_j(t)  /  sum_i u_k,i^2 q_k(t):
// the other modes' slip projected on mode k's slip pattern. A mode's amplitude
// outside its own kept span is continued with the decay rate at the span's end.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "jointlab/correlate/curve.h"
#include "jointlab/model/linear_modes.h"
#include "jointlab/model/model_file.h"

namespace jointlab::correlate {

/// How one model mode moves the joints and shows at a sensor.
struct ModeSlip {
  Eigen::VectorXd unit_slip;  ///< per Iwan joint: |relative displacement| per unit modal amplitude
  double sensor_scale = 0;    ///< measured amplitude per unit modal amplitude at the sensor
};

/// The slip pattern of elastic mode `mode` (1-based) of `model` (modes `lm` with the
/// joints at K_T), seen at matrix DOF `dof` as amplitude omega^power |phi|.
ModeSlip mode_slip(const model::Model& model, const model::LinearModes& lm, int mode,
                   Eigen::Index dof, int power);

/// share_k at each point of `curves[k]` (one hit; a null entry: that mode was not
/// measured in the hit and adds nothing).
Eigen::VectorXd slip_share(const std::vector<ModeSlip>& modes,
                           const std::vector<const Curve*>& curves, size_t k);

}  // namespace jointlab::correlate
