// The Iwan objective: QSMA of the set at given parameters against the measured backbones, its
// residuals, costs and model curves.
#include "jointlab/correlate/iwan_objective.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/core/text.h"
#include "jointlab/correlate/iwan_objective_detail.h"
#include "jointlab/correlate/qsma_at.h"
#include "jointlab/model/joint_condensation.h"
#include "jointlab/model/linear_modes.h"
#include "jointlab/model/qsma.h"

namespace jointlab::correlate {

using iwan_detail::stated_sigma;

namespace {

constexpr double kPenalty = 1e6;  // cost() of a parameter set the model cannot evaluate

// Every point of a target's curves by the DOF it is read at (-1: modal), each as (amplitude,
// (curve, point)).
using PointsByDof =
    std::map<Eigen::Index, std::vector<std::pair<double, std::pair<size_t, Eigen::Index>>>>;

// Every point of every curve of target t read at one DOF on one QSMA curve; false where mode R
// (column col of the modes) leaves a sensor still.
bool points_by_dof(const IwanTarget& t, const model::LinearModes& modes, int col, bool modal,
                   const std::vector<Sensor>& sensors, PointsByDof& by_dof) {
  for (size_t ci = 0; ci < t.curves.size(); ++ci) {
    const MeasuredBackbone& c = t.curves[ci];
    const Eigen::Index dof = modal ? -1 : sensors[c.sensor].dof;
    // A mode that leaves the sensor still (to rounding: 1e-8 of its largest motion) is
    // not the one measured there.
    const double ph = modal ? 1.0 : std::abs(modes.shapes(dof, col));
    if (!(ph > 1e-8 * modes.shapes.col(col).cwiseAbs().maxCoeff())) return false;
    for (Eigen::Index j = 0; j < c.amplitude.size(); ++j)
      by_dof[dof].push_back({c.amplitude(j), {ci, j}});
  }
  return true;
}

// The model at every point of target t (model_at[curve][point], pointing into `curves`): one QSMA
// curve per DOF over its sorted amplitudes (qsma_at.h), the slips at its ends gathered in
// slip_range (may be null); false where a curve does not reach every amplitude.
bool model_points(const model::JointCondensation& jc, const IwanTarget& t, int pw, bool matched,
                  bool from_scratch, PointsByDof& by_dof, Eigen::Vector2d* slip_range,
                  std::vector<std::vector<QsmaAtPoint>>& curves,
                  std::vector<std::vector<const model::QsmaPoint*>>& model_at) {
  curves.reserve(by_dof.size());
  model_at.resize(t.curves.size());
  for (size_t ci = 0; ci < t.curves.size(); ++ci)
    model_at[ci].resize(static_cast<size_t>(t.curves[ci].amplitude.size()));
  for (auto& [dof, order] : by_dof) {
    std::sort(order.begin(), order.end());
    std::vector<double> s(order.size());
    for (size_t i = 0; i < order.size(); ++i) s[i] = order[i].first;
    curves.push_back(
        qsma_at(jc, t.mode, pw, s,
                matched ? AmplitudeFrequency::kFirstHarmonic : AmplitudeFrequency::kSecant,
                from_scratch ? QsmaAtSolver::kBracketing : QsmaAtSolver::kNewton,
                dof < 0 ? std::nullopt : std::optional<Eigen::Index>(dof)));
    const std::vector<QsmaAtPoint>& at = curves.back();
    if (at.size() != s.size()) return false;
    if (slip_range) {
      (*slip_range)(0) = std::min((*slip_range)(0), at.front().point.max_slip);
      (*slip_range)(1) = std::max((*slip_range)(1), at.back().point.max_slip);
    }
    for (size_t i = 0; i < order.size(); ++i)
      model_at[order[i].second.first][static_cast<size_t>(order[i].second.second)] = &at[i].point;
  }
  return true;
}

// Target t's residuals from index k on (k advanced past them), weighted by the measured scatter
// (floored), the model's values (may be null) beside them; the damping residuals' positions and
// scales in z_index and z_scale (the structure's own damping is added after).
void target_residuals(const IwanTarget& t,
                      const std::vector<std::vector<const model::QsmaPoint*>>& model_at,
                      bool matched, double f_floor, double z_floor, double n_total, double* r,
                      double* values, int& k, std::vector<int>& z_index,
                      std::vector<double>& z_scale) {
  for (size_t ci = 0; ci < t.curves.size(); ++ci) {
    const MeasuredBackbone& c = t.curves[ci];
    for (Eigen::Index j = 0; j < c.amplitude.size(); ++j) {
      const model::QsmaPoint& q = *model_at[ci][static_cast<size_t>(j)];
      const double f = matched ? q.ringdown_frequency_hz : q.frequency_hz;
      const double z = !matched                               ? q.damping_ratio
                       : c.kind == BackboneKind::kSteppedSine ? q.harmonic_damping_ratio
                                                              : q.ringdown_damping_ratio;
      const Eigen::Vector2d stated = stated_sigma(c, j);
      const double sf = std::max(stated(0), f_floor * c.frequency_hz(j));
      const double sz = std::max(stated(1), z_floor * std::abs(c.damping_ratio(j)));
      if (values) {
        values[k] = f;
        values[k + 1] = z;
      }
      r[k++] = (f - c.frequency_hz(j)) / (sf * std::sqrt(n_total));
      if (sz > 0) {
        z_index.push_back(k);
        z_scale.push_back(1 / (sz * std::sqrt(n_total)));
      }
      r[k++] = sz > 0 ? (z - c.damping_ratio(j)) / (sz * std::sqrt(n_total)) : 0.0;
    }
  }
}

}  // namespace

IwanObjective::IwanObjective(const model::Model& model, const std::string& set,
                             const std::vector<Sensor>& sensors, std::vector<IwanTarget> targets,
                             const IwanUpdateOptions& options)
    : model_(&model),
      set_(set.starts_with("iwan.") ? set : "iwan." + set),
      sensors_(sensors),
      targets_(std::move(targets)),
      amplitude_(options.amplitude),
      f_floor_(options.frequency_floor),
      z_floor_(options.damping_floor),
      comparison_(options.comparison),
      fit_z_(options.fit_linear_damping),
      z_model_(model.modal_ratio),
      z_max_(options.linear_damping_max) {
  if (fit_z_ && !(z_max_ > 0 && z_max_ < 1)) {
    throw InputError(fmt::format(
        "update-iwan: the upper bound of the fitted modal damping ratio, {}, must be in (0, 1)",
        z_max_));
  }
  bool found = false;
  for (const model::Joint& j : model.joints) {
    if (j.element != set_) continue;
    if (!j.iwan) throw InputError(fmt::format("set '{}' is not an Iwan set", set_));
    if (!found) {
      Ks_ = j.stiffness;
      initial_ = {j.iwan->slip_force(), j.iwan->stiffness(), j.iwan->chi(), j.iwan->beta()};
      found = true;
    }
  }
  if (!found) throw InputError(fmt::format("no joint of the model uses the Iwan set '{}'", set_));
  if (targets_.empty()) throw InputError("no measured backbone to update against");
  int curve_index = 0;
  for (const IwanTarget& t : targets_) {
    if (t.mode < 1) throw InputError(fmt::format("mode {} must be >= 1", t.mode));
    if (t.curves.empty()) throw InputError(fmt::format("mode {}: no measured backbone", t.mode));
    for (const MeasuredBackbone& c : t.curves) {
      if (c.modal != t.curves.front().modal) {
        throw InputError(fmt::format(
            "mode {}: backbones of modal amplitude and of a sensor's amplitude cannot be fitted "
            "as one mode's target",
            t.mode));
      }
      if (!c.modal && (c.sensor < 0 || c.sensor >= static_cast<int>(sensors_.size()))) {
        throw InputError(fmt::format("mode {}: backbone sensor index out of range", t.mode));
      }
      const std::string name = !c.source.empty() ? c.source
                               : c.modal         ? std::string("modal amplitude")
                                                 : "channel " + sensors_[c.sensor].channel;
      const Eigen::Index n = c.amplitude.size();
      if (n == 0 || c.frequency_hz.size() != n || c.damping_ratio.size() != n ||
          c.frequency_std_hz.size() != n || c.damping_std.size() != n) {
        throw InputError(
            fmt::format("mode {}, {}: backbone columns empty or of unequal length", t.mode, name));
      }
      if (!(c.coverage_factor >= 1 && std::isfinite(c.coverage_factor))) {
        throw InputError(fmt::format("mode {}, {}: coverage factor {} is not a finite number >= 1",
                                     t.mode, name, c.coverage_factor));
      }
      if ((c.amplitude.array() <= 0).any() || (c.frequency_hz.array() <= 0).any() ||
          !c.amplitude.allFinite() || !c.frequency_hz.allFinite() || !c.damping_ratio.allFinite()) {
        throw InputError(fmt::format(
            "mode {}, {}: amplitudes and frequencies must be finite and > 0", t.mode, name));
      }
      residual_count_ += 2 * static_cast<int>(n);
      residual_curve_.insert(residual_curve_.end(), 2 * static_cast<size_t>(n), curve_index++);
      for (Eigen::Index j = 0; j < n; ++j) {
        residual_amplitude_.push_back(c.amplitude(j));
        residual_amplitude_.push_back(c.amplitude(j));
      }
    }
  }
  // The linear model's set-up shared by every evaluation; a model it cannot serve (a mode
  // it does not have) is evaluated from scratch, which says what is wrong.
  int highest = 0;
  for (const IwanTarget& t : targets_) highest = std::max(highest, t.mode);
  try {
    set_model_ = std::make_shared<const model::IwanSetModel>(model, set_, highest);
  } catch (const InputError&) {
    set_model_.reset();
  }
}

std::vector<ModelBackbone> IwanObjective::model_curves(const model::IwanParameters& p, double z,
                                                       int points) const {
  const model::Model m = apply(p, z);
  int highest = 0;
  for (const IwanTarget& t : targets_) highest = std::max(highest, t.mode);
  model::ModesOptions mo;
  mo.elastic_count = highest;
  const model::JointCondensation jc(m, mo);
  std::vector<ModelBackbone> out;
  for (const IwanTarget& t : targets_) {
    double lo = INFINITY, hi = 0;
    for (const MeasuredBackbone& c : t.curves) {
      lo = std::min(lo, c.amplitude.minCoeff());
      hi = std::max(hi, c.amplitude.maxCoeff());
    }
    const MeasuredBackbone& first = t.curves.front();
    const std::optional<Eigen::Index> dof =
        first.modal ? std::nullopt : std::optional<Eigen::Index>(sensors_[first.sensor].dof);
    const int pw = first.modal ? 0 : amplitude_power(amplitude_);
    try {
      out.push_back(model_backbone(jc, t.mode, dof, pw, first.kind, comparison_, lo, hi, points));
    } catch (const InputError&) {
      ModelBackbone none;
      none.clipped = true;
      out.push_back(none);
    }
  }
  return out;
}

model::Model IwanObjective::apply(const model::IwanParameters& p, double z) const {
  model::Model m = apply(p);
  m.modal_ratio = z;
  return m;
}

model::Model IwanObjective::apply(const model::IwanParameters& p) const {
  model::Model m = *model_;
  for (model::Joint& j : m.joints) {
    if (j.element != set_) continue;
    j.stiffness = p.Kt;
    j.iwan = model::Iwan(p);
  }
  return m;
}

bool IwanObjective::residuals(const model::IwanParameters& p, double* r) const {
  return evaluate(p, r, nullptr, false);
}

bool IwanObjective::residuals_from_scratch(const model::IwanParameters& p, double* r) const {
  return evaluate(p, r, nullptr, true);
}

bool IwanObjective::residuals_at(const model::IwanParameters& p, double z, double* r) const {
  return evaluate(p, r, nullptr, false, &z);
}

std::optional<Eigen::Vector2d> IwanObjective::rms_errors(const model::IwanParameters& p,
                                                         double z) const {
  std::vector<double> r(residual_count_), v(residual_count_);
  if (!evaluate(p, r.data(), nullptr, false, &z, nullptr, v.data())) return std::nullopt;
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  int k = 0;
  for (const IwanTarget& t : targets_) {
    for (const MeasuredBackbone& c : t.curves) {
      for (Eigen::Index j = 0; j < c.amplitude.size(); ++j, k += 2) {
        sum(0) += std::pow(v[k] / c.frequency_hz(j) - 1, 2);
        sum(1) += std::pow(v[k + 1] / c.damping_ratio(j) - 1, 2);
      }
    }
  }
  return (sum / (residual_count_ / 2.0)).cwiseSqrt();
}

Eigen::Vector2d IwanObjective::constant_rms_errors() const {
  // The constant c minimising sum ((c - y_j) / y_j)^2 is sum (1/y_j) / sum (1/y_j^2).
  Eigen::Vector2d out;
  for (int part = 0; part < 2; ++part) {
    double s1 = 0, s2 = 0;
    std::vector<double> y;
    for (const IwanTarget& t : targets_)
      for (const MeasuredBackbone& c : t.curves)
        for (Eigen::Index j = 0; j < c.amplitude.size(); ++j)
          y.push_back(part == 0 ? c.frequency_hz(j) : c.damping_ratio(j));
    for (double v : y) s1 += 1 / v, s2 += 1 / (v * v);
    const double best = s1 / s2;
    double e = 0;
    for (double v : y) e += std::pow(best / v - 1, 2);
    out(part) = std::sqrt(e / static_cast<double>(y.size()));
  }
  return out;
}

std::optional<double> IwanObjective::linear_damping(const model::IwanParameters& p) const {
  std::vector<double> r(residual_count_);
  double z = 0;
  if (!evaluate(p, r.data(), nullptr, false, nullptr, &z)) return std::nullopt;
  return z;
}

Eigen::Vector2d IwanObjective::slip_range(const model::IwanParameters& p) const {
  std::vector<double> r(residual_count_);
  Eigen::Vector2d slip(INFINITY, 0);
  return evaluate(p, r.data(), &slip, false) ? slip : Eigen::Vector2d::Zero();
}

bool IwanObjective::evaluate(const model::IwanParameters& p, double* r, Eigen::Vector2d* slip_range,
                             bool from_scratch, const double* z_fixed, double* z_used,
                             double* values) const {
  ++evaluations_;
  if (!model::iwan_parameter_error(p).empty()) return false;
  const double n_total = residual_count_ / 2.0;
  // The damping residuals are those of the joints alone plus the structure's own Z, added
  // below: r_z,j = (zeta_J,j + Z - zeta_j) / (sigma_z,j sqrt(N)). Their positions and scales.
  std::vector<int> z_index;
  std::vector<double> z_scale;
  z_index.reserve(static_cast<size_t>(n_total));
  z_scale.reserve(static_cast<size_t>(n_total));
  try {
    std::optional<model::JointCondensation> shared;
    if (!from_scratch && set_model_) shared = set_model_->at(p);
    model::JointCondensation& jc = shared ? *shared : shared.emplace(apply(p));
    jc.set_linear_damping(0);
    const model::LinearModes& modes = jc.modes();
    int k = 0;
    for (const IwanTarget& t : targets_) {
      if (t.mode > jc.elastic_count()) return false;
      const int col = modes.rigid_count + t.mode - 1;
      // A modal amplitude is q itself (power 0); a sensor's is |u_d| w^p, u_d the QSMA
      // deflection at its DOF d (not |phi_R[d]| q w^p: once the joints slip the deflected
      // shape leaves the linear mode's, qsma_at.h).
      const bool modal = t.curves.front().modal;
      const int pw = modal ? 0 : amplitude_power(amplitude_);
      PointsByDof by_dof;
      if (!points_by_dof(t, modes, col, modal, sensors_, by_dof)) return false;
      const bool matched = comparison_ == IwanComparison::kMatched;
      std::vector<std::vector<QsmaAtPoint>> curves;  // kept: model_at points into them
      std::vector<std::vector<const model::QsmaPoint*>> model_at;
      if (!model_points(jc, t, pw, matched, from_scratch, by_dof, slip_range, curves, model_at))
        return false;
      target_residuals(t, model_at, matched, f_floor_, z_floor_, n_total, r, values, k, z_index,
                       z_scale);
    }
  } catch (const InputError&) {
    return false;
  }
  // The structure's own damping: given, the model's, or the best in [0, z_max] (the residuals
  // are linear in Z with slopes z_scale: Z = -sum s_j r_j / sum s_j^2 minimises them).
  double z = z_fixed ? *z_fixed : z_model_;
  if (!z_fixed && fit_z_) {
    double num = 0, den = 0;
    for (size_t i = 0; i < z_index.size(); ++i) {
      num -= z_scale[i] * r[z_index[i]];
      den += z_scale[i] * z_scale[i];
    }
    z = den > 0 ? std::clamp(num / den, 0.0, z_max_) : 0.0;
  }
  for (size_t i = 0; i < z_index.size(); ++i) r[z_index[i]] += z * z_scale[i];
  if (values)
    for (int i = 1; i < residual_count_; i += 2) values[i] += z;
  if (z_used) *z_used = z;
  for (int i = 0; i < residual_count_; ++i) {
    if (!std::isfinite(r[i])) return false;
  }
  return true;
}

bool IwanObjective::residuals_with_structure_stiffness(const model::IwanParameters& p, double z,
                                                       double factor, double* r) const {
  model::Model m = *model_;
  m.stiffness *= factor;
  IwanUpdateOptions o;
  o.amplitude = amplitude_;
  o.comparison = comparison_;
  o.frequency_floor = f_floor_;
  o.damping_floor = z_floor_;
  try {
    const IwanObjective scaled(m, set_, sensors_, targets_, o);
    return scaled.residuals_at(p, z, r);
  } catch (const InputError&) {
    return false;
  }
}

std::optional<double> IwanObjective::try_cost(const model::IwanParameters& p) const {
  std::vector<double> r(residual_count_);
  if (!residuals(p, r.data())) return std::nullopt;
  double s = 0;
  for (double v : r) s += v * v;
  return s;
}

double IwanObjective::cost(const model::IwanParameters& p) const {
  return try_cost(p).value_or(kPenalty);
}

Eigen::Vector3i IwanObjective::floored_points() const {
  Eigen::Vector3i out = Eigen::Vector3i::Zero();
  for (const IwanTarget& t : targets_) {
    for (const MeasuredBackbone& c : t.curves) {
      for (Eigen::Index j = 0; j < c.amplitude.size(); ++j) {
        ++out(0);
        const Eigen::Vector2d stated = stated_sigma(c, j);
        out(1) += stated(0) > 0 && stated(0) < f_floor_ * c.frequency_hz(j);
        out(2) += stated(1) > 0 && stated(1) < z_floor_ * std::abs(c.damping_ratio(j));
      }
    }
  }
  return out;
}

}  // namespace jointlab::correlate
