// The linear objective at a point: pairs (by the rules, or given), residuals and their analytic
// Jacobian (linear_update.h: evaluate_linear, evaluate_pairs), and the measured modes' and
// evaluations' own accessors.
#include <cmath>
#include <numbers>
#include <optional>

#include "jointlab/correlate/linear_problem.h"
#include "jointlab/correlate/linear_update.h"

namespace jointlab::correlate {
namespace {

// Mode i's own name among `ids`, or its position i + 1 where it has none.
std::string id_or_position(const std::vector<std::string>& ids, Eigen::Index i) {
  const auto k = static_cast<size_t>(i);
  return k < ids.size() && !ids[k].empty() ? ids[k] : std::to_string(i + 1);
}

// Each model mode's squared norm at the sensors.
Eigen::VectorXd norms_at_sensors(const Eigen::MatrixXd& at_sensors) {
  return at_sensors.colwise().squaredNorm().transpose();
}

// Whether each measured mode has a shape a MAC can read: entries at two sensors or more. At one
// sensor the MAC is 1 against every model mode that moves there, so it tells nothing, and the
// visibility rule would turn on that one number: a measured mode near a node of the sensor
// (5e-4 of the others' entries) was paired with the one of two model modes 4e-5 apart in
// frequency that moved there, and the fit then tuned a set that mode alone saw (spring.rz,
// 100 -> 2129 N m/rad, "converged" with 7 % uncertainty). Such a mode pairs by frequency alone.
std::vector<bool> shapes_given(const MeasuredModes& measured) {
  std::vector<bool> out(static_cast<size_t>(measured.frequency_hz.size()));
  for (Eigen::Index i = 0; i < measured.frequency_hz.size(); ++i) {
    const auto entries = (measured.shapes.col(i).array().abs() > 0.0).count();
    out[static_cast<size_t>(i)] = entries >= 2;
  }
  return out;
}

}  // namespace

std::string MeasuredModes::id(Eigen::Index i) const { return id_or_position(ids, i); }

MeasuredModes MeasuredModes::columns(const std::vector<Eigen::Index>& keep) const {
  MeasuredModes out;
  out.frequency_hz = frequency_hz(keep);
  out.shapes = shapes(Eigen::all, keep);
  for (const Eigen::Index k : keep) {
    const auto u = static_cast<size_t>(k);
    out.labels.push_back(u < labels.size() ? labels[u] : std::string());
    out.ids.push_back(id(k));
  }
  if (frequency_std.size() == frequency_hz.size()) out.frequency_std = frequency_std(keep);
  return out;
}

std::string LinearEvaluation::measured_id(Eigen::Index i) const {
  return id_or_position(measured_ids, i);
}

double LinearEvaluation::max_error() const {
  double m = 0;
  for (const ModePair& p : pairing.pairs) m = std::max(m, std::abs(residuals(p.measured)));
  return m;
}

double LinearEvaluation::weighted_squared_norm() const {
  if (weights.size() != residuals.size()) return residuals.squaredNorm();
  return residuals.cwiseProduct(weights).squaredNorm();
}

std::optional<double> LinearEvaluation::pair_mac(Eigen::Index i) const {
  const int j = pairing.model_for(static_cast<int>(i));
  const auto k = static_cast<size_t>(i);
  if (j < 0 || mac.size() == 0 || k >= mac_reads_shape.size() || !mac_reads_shape[k]) return {};
  return mac(i, j);
}

LinearEvaluation evaluate_pairs(const StiffnessSets& sets, const std::vector<Sensor>& sensors,
                                const MeasuredModes& measured,
                                const Eigen::Ref<const Eigen::VectorXd>& theta,
                                const ElasticModes& modes, const std::vector<int>& columns) {
  const int m = static_cast<int>(measured.frequency_hz.size());
  LinearEvaluation e;
  e.model_at_sensors = shapes_at_sensors(sensors, modes.shapes);
  e.mac = mac_matrix(measured.shapes, e.model_at_sensors);
  e.all_model_frequency_hz = modes.frequency_hz;
  e.measured_frequency_hz = measured.frequency_hz;
  e.measured_ids = measured.ids;
  e.mac_reads_shape = shapes_given(measured);
  e.model_frequency_hz = Eigen::VectorXd::Zero(m);
  e.residuals = Eigen::VectorXd::Zero(m);
  e.jacobian = Eigen::MatrixXd::Zero(m, sets.size());
  std::vector<char> used(static_cast<size_t>(modes.frequency_hz.size()), 0);
  for (int i = 0; i < m; ++i) {
    const int j = i < static_cast<int>(columns.size()) ? columns[static_cast<size_t>(i)] : -1;
    if (j < 0) {
      e.pairing.unpaired_measured.push_back(i);
      continue;
    }
    used[static_cast<size_t>(j)] = 1;
    e.pairing.pairs.push_back({i, j, e.mac(i, j)});
    const double f = modes.frequency_hz(j);
    const double fe = measured.frequency_hz(i);
    e.model_frequency_hz(i) = f;
    e.residuals(i) = (f - fe) / fe;
    if (f <= 0) continue;
    const Eigen::VectorXd v = modes.shapes.col(j);
    for (int k = 0; k < sets.size(); ++k) {
      const double dw2 = v.dot(sets.pattern(k) * v);
      e.jacobian(i, k) = theta(k) * dw2 / (8.0 * std::numbers::pi * std::numbers::pi * f * fe);
    }
  }
  for (size_t j = 0; j < used.size(); ++j)
    if (!used[j]) e.pairing.unpaired_model.push_back(static_cast<int>(j));
  return e;
}

namespace detail {

// The evaluation at theta, `modes` its elastic modes, with the pairs made afresh by the rules;
// `columns` receives the model column of each measured mode (-1: unpaired).
LinearEvaluation evaluate_by_rules(const StiffnessSets& sets, const std::vector<Sensor>& sensors,
                                   const MeasuredModes& measured,
                                   const Eigen::Ref<const Eigen::VectorXd>& theta,
                                   const ElasticModes& modes, const PairingRules& rules,
                                   std::vector<int>& columns) {
  const Eigen::MatrixXd at = shapes_at_sensors(sensors, modes.shapes);
  std::vector<std::string> names;
  for (Eigen::Index i = 0; i < measured.frequency_hz.size(); ++i) names.push_back(measured.id(i));
  const RulePairing rp =
      pair_by_rules(mac_matrix(measured.shapes, at), measured.frequency_hz, shapes_given(measured),
                    modes.frequency_hz, norms_at_sensors(at), rules, names);
  columns.assign(static_cast<size_t>(measured.frequency_hz.size()), -1);
  for (const ModePair& p : rp.pairing.pairs) columns[static_cast<size_t>(p.measured)] = p.model;
  LinearEvaluation e = evaluate_pairs(sets, sensors, measured, theta, modes, columns);
  e.hidden = rp.hidden;
  e.ambiguity = rp.ambiguity;
  e.ties = rp.ties;
  return e;
}

}  // namespace detail

using detail::evaluate_by_rules;

LinearEvaluation evaluate_linear(const StiffnessSets& sets, const model::Model& model,
                                 const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                                 const Eigen::Ref<const Eigen::VectorXd>& theta,
                                 const PairingRules& rules) {
  std::vector<int> columns;
  return evaluate_by_rules(sets, sensors, measured, theta,
                           elastic_modes(model.mass, sets.stiffness(theta)), rules, columns);
}

LinearEvaluation evaluate_linear(const StiffnessSets& sets, const model::Model& model,
                                 const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                                 const Eigen::Ref<const Eigen::VectorXd>& theta,
                                 double mac_threshold, double frequency_window) {
  PairingRules rules;
  rules.mac_threshold = mac_threshold;
  rules.frequency_window = frequency_window;
  return evaluate_linear(sets, model, sensors, measured, theta, rules);
}

std::vector<AliasedModes> aliased_modes(const Eigen::Ref<const Eigen::MatrixXd>& at_sensors,
                                        double threshold) {
  std::vector<AliasedModes> out;
  for (Eigen::Index a = 0; a < at_sensors.cols(); ++a) {
    for (Eigen::Index b = a + 1; b < at_sensors.cols(); ++b) {
      const double na = at_sensors.col(a).squaredNorm(), nb = at_sensors.col(b).squaredNorm();
      if (!(na > 0 && nb > 0)) continue;
      const double d = at_sensors.col(a).dot(at_sensors.col(b));
      const double v = d * d / (na * nb);
      if (v >= threshold) out.push_back({static_cast<int>(a), static_cast<int>(b), v});
    }
  }
  return out;
}

}  // namespace jointlab::correlate
