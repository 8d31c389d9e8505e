#include "jointlab/correlate/mode_interference.h"

#include <cassert>
#include <cmath>
#include <numbers>

namespace jointlab::correlate {

namespace {

// ln of a curve's amplitude at time t: linear in time between points, continued
// beyond either end with the decay rate sigma = zeta 2 pi f of the end point.
double log_amplitude_at(const Curve& c, double t) {
  const Eigen::Index n = c.time_s.size();
  assert(n > 0 && c.amplitude.size() == n);
  const auto decay = [&](Eigen::Index i) {
    return c.damping(i) * 2 * std::numbers::pi * c.frequency_hz(i);
  };
  if (t <= c.time_s(0)) return std::log(c.amplitude(0)) + decay(0) * (c.time_s(0) - t);
  if (t >= c.time_s(n - 1)) {
    return std::log(c.amplitude(n - 1)) - decay(n - 1) * (t - c.time_s(n - 1));
  }
  Eigen::Index i = 1;
  while (c.time_s(i) < t) ++i;
  const double w = (t - c.time_s(i - 1)) / (c.time_s(i) - c.time_s(i - 1));
  return (1 - w) * std::log(c.amplitude(i - 1)) + w * std::log(c.amplitude(i));
}

}  // namespace

ModeSlip mode_slip(const model::Model& model, const model::LinearModes& lm, int mode,
                   Eigen::Index dof, int power) {
  const int col = lm.rigid_count + mode - 1;
  assert(mode >= 1 && col < lm.size());
  const Eigen::VectorXd phi = lm.shapes.col(col);
  std::vector<double> slip;
  for (const model::Joint& j : model.joints) {
    if (!j.iwan) continue;
    slip.push_back(std::abs(phi(j.a) - (j.b == model::kGround ? 0.0 : phi(j.b))));
  }
  ModeSlip s;
  s.unit_slip =
      Eigen::Map<const Eigen::VectorXd>(slip.data(), static_cast<Eigen::Index>(slip.size()));
  s.sensor_scale = std::abs(phi(dof)) * std::pow(std::sqrt(lm.omega2(col)), power);
  return s;
}

Eigen::VectorXd slip_share(const std::vector<ModeSlip>& modes,
                           const std::vector<const Curve*>& curves, size_t k) {
  assert(modes.size() == curves.size() && k < curves.size() && curves[k]);
  const Curve& own = *curves[k];
  const Eigen::VectorXd& uk = modes[k].unit_slip;
  const double own_norm = uk.squaredNorm();
  Eigen::VectorXd share = Eigen::VectorXd::Zero(own.amplitude.size());
  if (!(own_norm > 0) || !(modes[k].sensor_scale > 0)) return share;
  for (Eigen::Index p = 0; p < own.amplitude.size(); ++p) {
    const double qk = own.amplitude(p) / modes[k].sensor_scale;
    double other = 0;
    for (size_t j = 0; j < curves.size(); ++j) {
      if (j == k || !curves[j] || curves[j]->time_s.size() == 0 || !(modes[j].sensor_scale > 0))
        continue;
      const double qj =
          std::exp(log_amplitude_at(*curves[j], own.time_s(p))) / modes[j].sensor_scale;
      other += uk.dot(modes[j].unit_slip) * qj;
    }
    share(p) = other / (own_norm * qk);
  }
  return share;
}

}  // namespace jointlab::correlate
