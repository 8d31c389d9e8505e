// Measured and model backbones of the Iwan update: the amplitude quantity's power of omega and
// a model's backbone as a measured one would show it.
#include "jointlab/correlate/iwan_backbone.h"

#include <cassert>
#include <cmath>
#include <vector>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/core/text.h"
#include "jointlab/correlate/qsma_at.h"
#include "jointlab/model/qsma.h"

namespace jointlab::correlate {

int amplitude_power(AmplitudeQuantity q) {
  return q == AmplitudeQuantity::kDisplacement ? 0 : q == AmplitudeQuantity::kVelocity ? 1 : 2;
}

AmplitudeQuantity amplitude_quantity(Quantity q) {
  assert(q != Quantity::kForce);
  return q == Quantity::kDisplacement ? AmplitudeQuantity::kDisplacement
         : q == Quantity::kVelocity   ? AmplitudeQuantity::kVelocity
                                      : AmplitudeQuantity::kAcceleration;
}

ModelBackbone model_backbone(const model::JointCondensation& jc, int mode,
                             std::optional<Eigen::Index> dof, int power, BackboneKind kind,
                             IwanComparison comparison, double a_lo, double a_hi, int points) {
  if (mode < 1 || mode > jc.elastic_count())
    throw InputError(fmt::format("mode {} does not exist: the model has {}", mode,
                                 counted(jc.elastic_count(), "elastic mode")));
  if (!(a_lo > 0) || !(a_hi >= a_lo) || points < 2)
    throw InputError("model backbone: need 0 < a_lo <= a_hi and two points or more");
  const bool matched = comparison == IwanComparison::kMatched;
  // The amplitude as fitted (evaluate()): q itself, or the deflection at the sensor's DOF.
  std::vector<double> s(static_cast<size_t>(points));
  for (int i = 0; i < points; ++i)
    s[static_cast<size_t>(i)] = a_lo * std::pow(a_hi / a_lo, i / (points - 1.0));
  const std::vector<QsmaAtPoint> at =
      qsma_at(jc, mode, power, s,
              matched ? AmplitudeFrequency::kFirstHarmonic : AmplitudeFrequency::kSecant,
              QsmaAtSolver::kNewton, dof);
  ModelBackbone out;
  std::vector<size_t> keep;
  for (size_t i = 0; i < at.size(); ++i)
    if (at[i].reached) keep.push_back(i);
  out.clipped = keep.size() < s.size();
  const Eigen::Index n = static_cast<Eigen::Index>(keep.size());
  out.amplitude.resize(n);
  out.frequency_hz.resize(n);
  out.damping_ratio.resize(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    const model::QsmaPoint& q = at[keep[static_cast<size_t>(j)]].point;
    out.amplitude(j) = s[keep[static_cast<size_t>(j)]];
    out.frequency_hz(j) = matched ? q.ringdown_frequency_hz : q.frequency_hz;
    out.damping_ratio(j) = !matched                             ? q.damping_ratio
                           : kind == BackboneKind::kSteppedSine ? q.harmonic_damping_ratio
                                                                : q.ringdown_damping_ratio;
  }
  return out;
}

}  // namespace jointlab::correlate
