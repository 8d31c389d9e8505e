#include "jointlab/correlate/linear_update.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>
#include <optional>

#include <ceres/ceres.h>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <boost/math/distributions/chi_squared.hpp>

#include "jointlab/core/error.h"
#include "jointlab/core/parallel.h"
#include "jointlab/correlate/shape_checks.h"
#include "jointlab/model/linear_modes.h"

namespace jointlab::correlate {
namespace {

using Triplets = std::vector<Eigen::Triplet<double>>;

void add_joint(Triplets& t, const model::Joint& j, double k) {
  t.emplace_back(j.a, j.a, k);
  if (j.b != model::kGround) {
    t.emplace_back(j.b, j.b, k);
    t.emplace_back(j.a, j.b, -k);
    t.emplace_back(j.b, j.a, -k);
  }
}

}  // namespace

StiffnessSets::StiffnessSets(const model::Model& model, std::vector<std::string> names)
    : model_(&model), names_(std::move(names)) {
  for (size_t k = 0; k < names_.size(); ++k)
    for (size_t l = 0; l < k; ++l)
      if (names_[k] == names_[l])
        throw InputError(fmt::format("parameter set '{}' is named twice", names_[k]));
  const Eigen::Index n = model.size();
  initial_ = Eigen::VectorXd::Zero(size());
  std::vector<Triplets> pat(names_.size());
  Triplets fixed;
  for (const model::Joint& j : model.joints) {
    const auto it = std::find(names_.begin(), names_.end(), j.element);
    if (it == names_.end()) {
      add_joint(fixed, j, j.stiffness);
    } else {
      const auto k = it - names_.begin();
      add_joint(pat[k], j, 1.0);
      initial_(k) = j.stiffness;
    }
  }
  for (int k = 0; k < size(); ++k) {
    if (pat[k].empty()) {
      throw InputError(
          fmt::format("parameter set '{}': no joint of the model uses this element", names_[k]));
    }
    patterns_.emplace_back(n, n);
    patterns_.back().setFromTriplets(pat[k].begin(), pat[k].end());
  }
  fixed_.resize(n, n);
  fixed_.setFromTriplets(fixed.begin(), fixed.end());
  fixed_ += model.stiffness;
}

Eigen::SparseMatrix<double> StiffnessSets::stiffness(
    const Eigen::Ref<const Eigen::VectorXd>& theta) const {
  Eigen::SparseMatrix<double> k = fixed_;
  for (int i = 0; i < size(); ++i) k += theta(i) * patterns_[i];
  return k;
}

model::Model StiffnessSets::apply(const Eigen::Ref<const Eigen::VectorXd>& theta) const {
  model::Model out = *model_;
  for (model::Joint& j : out.joints) {
    const auto it = std::find(names_.begin(), names_.end(), j.element);
    if (it == names_.end()) continue;
    const double k = theta(it - names_.begin());
    j.stiffness = k;
    if (j.iwan) {
      j.iwan = model::Iwan(j.iwan->slip_force(), k, j.iwan->chi(), j.iwan->beta());
    }
  }
  return out;
}

namespace {

// Mode i's own name among `ids`, or its position i + 1 where it has none.
std::string id_or_position(const std::vector<std::string>& ids, Eigen::Index i) {
  const auto k = static_cast<size_t>(i);
  return k < ids.size() && !ids[k].empty() ? ids[k] : std::to_string(i + 1);
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

namespace {

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

namespace {

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

}  // namespace

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

std::string LinearUpdateOptions::error() const {
  if (!(mac_threshold > 0 && mac_threshold <= 1)) return "mac_threshold must be in (0, 1]";
  if (!(lower_factor > 0 && lower_factor < 1)) return "lower_factor must be in (0, 1)";
  if (!(upper_factor > 1) || !std::isfinite(upper_factor)) return "upper_factor must be > 1";
  if (max_iterations < 1) return "max_iterations must be >= 1";
  if (!(tolerance >= 0)) return "tolerance must be >= 0";
  if (!(flat_sensitivity > 0)) return "flat_sensitivity must be > 0";
  if (!(frequency_std > 0)) return "frequency_std must be > 0";
  if (!(sweep_decades > 0)) return "sweep_decades must be > 0";
  if (sweep_points < 2) return "sweep_points must be >= 2";
  if (!(frequency_window >= 0) || !std::isfinite(frequency_window))
    return "frequency_window must be >= 0";
  if (!(visibility >= 0 && visibility < 1)) return "visibility must be in [0, 1)";
  if (!(alias_mac > 0 && alias_mac <= 1)) return "alias_mac must be in (0, 1]";
  for (const ParameterBound& b : bounds) {
    if (!(b.lower > 0 && b.lower < b.upper) || !std::isfinite(b.upper)) {
      return fmt::format("bounds of '{}': need 0 < lower < upper", b.name);
    }
  }
  for (const ParameterHold& h : holds) {
    if (!(h.value >= 0) || !std::isfinite(h.value))
      return fmt::format("hold of '{}': the value must be a stiffness > 0", h.name);
  }
  if (rule == LinearRule::kSmallest) {
    if (!(tolerance > 0)) return "the smallest rule needs a tolerance > 0";
    if (smallest_set.empty()) return "the smallest rule needs the set to minimise";
  }
  return "";
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

namespace {

// A point of the fit whose pairs are known: ln theta, the elastic modes there, and the
// model column each measured mode is paired with (-1: unpaired).
struct TrackedPoint {
  Eigen::VectorXd x;
  ElasticModes modes;
  std::vector<int> columns;
};

void check_measured(const std::vector<Sensor>& sensors, const MeasuredModes& measured) {
  if (measured.shapes.rows() != static_cast<Eigen::Index>(sensors.size()) ||
      measured.shapes.cols() != measured.frequency_hz.size()) {
    throw InputError(fmt::format(
        "measured modes: {} shapes of {} sensors for {} frequencies, expected {} sensors",
        measured.shapes.cols(), measured.shapes.rows(), measured.frequency_hz.size(),
        sensors.size()));
  }
  // "measured mode 2", with its label when that says more ("measured mode 2 (band2)").
  auto name = [&](Eigen::Index i) {
    const std::string plain = fmt::format("measured mode {}", measured.id(i));
    if (static_cast<size_t>(i) >= measured.labels.size()) return plain;
    const std::string& l = measured.labels[static_cast<size_t>(i)];
    if (l.empty() || l == fmt::format("mode {}", measured.id(i)) || l == measured.id(i))
      return plain;
    return fmt::format("{} ({})", plain, l);
  };
  bool any_shape = false;
  for (Eigen::Index i = 0; i < measured.frequency_hz.size(); ++i) {
    if (!(measured.frequency_hz(i) > 0) || !std::isfinite(measured.frequency_hz(i))) {
      throw InputError(fmt::format("{}: frequency must be > 0", name(i)));
    }
    if (!measured.shapes.col(i).allFinite())
      throw InputError(
          fmt::format("{}: its shape is not a finite number at every sensor", name(i)));
    any_shape = any_shape || measured.shapes.col(i).squaredNorm() > 0;
  }
  if (!any_shape) return;  // frequencies only: pairs by the nearest frequency
  for (Eigen::Index i = 0; i < measured.frequency_hz.size(); ++i) {
    if (measured.shapes.col(i).squaredNorm() > 0) continue;
    throw InputError(fmt::format(
        "{} at {:.6g} Hz: its shape is zero at every sensor, so no MAC can pair it (0/0); give "
        "its shape or leave the mode out",
        name(i), measured.frequency_hz(i)));
  }
}

// The index of `name` among the sets updated; InputError "`what`: ..." if it is not one.
int set_index(const std::vector<std::string>& names, const std::string& name,
              const std::string& what) {
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) {
    throw InputError(fmt::format("{}: '{}' is not one of the sets updated", what, name));
  }
  return static_cast<int>(it - names.begin());
}

double rms_of(const LinearEvaluation& e) {
  if (e.pairing.pairs.empty()) return 0;
  return std::sqrt(e.residuals.squaredNorm() / static_cast<double>(e.pairing.pairs.size()));
}

// The updating problem: the sets, the data, the options and the bounds of each set.
struct LinearProblem {
  const StiffnessSets& sets;
  const model::Model& model;
  const std::vector<std::string>& names;
  const std::vector<Sensor>& sensors;
  const MeasuredModes& measured;
  const LinearUpdateOptions& options;
  Eigen::VectorXd start, lower, upper;
  TrackingOptions tracking;
  // Per measured mode, w_i = frequency_std / sigma_i, sigma_i its own uncertainty where wider.
  Eigen::VectorXd weight;

  int size() const { return sets.size(); }

  PairingRules rules() const {
    PairingRules r;
    r.mac_threshold = options.mac_threshold;
    r.frequency_window = options.frequency_window;
    r.visibility = options.visibility;
    return r;
  }

  // The point at x with its pairs made afresh by the rules; e receives the evaluation there.
  TrackedPoint fresh(const Eigen::VectorXd& x, LinearEvaluation& e) const {
    const Eigen::VectorXd theta = x.array().exp();
    TrackedPoint p{x, elastic_modes(model.mass, sets.stiffness(theta)), {}};
    e = evaluate_by_rules(sets, sensors, measured, theta, p.modes, rules(), p.columns);
    e.weights = weight;
    return p;
  }

  // `from` moved to x, every pair followed by its full shape; nullopt when one is lost.
  std::optional<TrackedPoint> move(const TrackedPoint& from, const Eigen::VectorXd& x,
                                   int substeps = 1) const {
    if (x == from.x) return from;
    TrackingOptions t = tracking;
    t.substeps = substeps;
    const Eigen::VectorXd dx = x - from.x;
    const auto path = [&](double s) -> Eigen::SparseMatrix<double> {
      return sets.stiffness((from.x + s * dx).array().exp());
    };
    std::optional<FollowedModes> f;
    try {
      f = follow_path(path, model.mass, from.modes, from.columns, t);
    } catch (const InputError&) {
      return std::nullopt;  // an indefinite K on the way
    }
    if (!f) return std::nullopt;
    return TrackedPoint{x, std::move(f->modes), std::move(f->columns)};
  }

  LinearEvaluation evaluate(const TrackedPoint& p) const {
    LinearEvaluation e =
        evaluate_pairs(sets, sensors, measured, p.x.array().exp(), p.modes, p.columns);
    e.weights = weight;
    return e;
  }

  // Each pair's row of the Jacobian over its own mode's sigma (times frequency_std): the rows of
  // the chi-square's (J^T W^2 J).
  Eigen::MatrixXd weighted_jacobian(const LinearEvaluation& e) const {
    return weight.asDiagonal() * e.jacobian;
  }
};

// The pairs followed from the last accepted step: each Ceres evaluation moves the reference
// point to the trial x by following shapes; each accepted step becomes the new reference.
class Follower {
 public:
  explicit Follower(const LinearProblem& p, TrackedPoint start) : p_(p), ref_(std::move(start)) {}
  const TrackedPoint* at(const Eigen::VectorXd& x) {
    for (const TrackedPoint& c : cache_)
      if (c.x == x) return &c;
    std::optional<TrackedPoint> moved = p_.move(ref_, x);
    if (!moved) return nullptr;
    if (cache_.size() >= 4) cache_.erase(cache_.begin());
    cache_.push_back(std::move(*moved));
    return &cache_.back();
  }
  // The accepted step: the new reference (false when its pairs cannot be followed there).
  bool accept(const Eigen::VectorXd& x) {
    const TrackedPoint* p = at(x);
    if (!p) return false;
    ref_ = *p;
    return true;
  }
  const TrackedPoint& reference() const { return ref_; }

 private:
  const LinearProblem& p_;
  TrackedPoint ref_;
  std::vector<TrackedPoint> cache_;
};

// Ceres cost on x = ln theta with the analytic Jacobian, pairs followed by shape.
class LinearCost : public ceres::CostFunction {
 public:
  LinearCost(const LinearProblem& p, Follower& follower) : p_(p), follower_(follower) {
    set_num_residuals(static_cast<int>(p.measured.frequency_hz.size()));
    mutable_parameter_block_sizes()->push_back(p.size());
  }
  bool Evaluate(double const* const* x, double* residuals, double** jacobians) const override {
    const int n = p_.size();
    const Eigen::VectorXd xv = Eigen::Map<const Eigen::VectorXd>(x[0], n);
    const TrackedPoint* at = follower_.at(xv);
    if (!at) return false;  // a pair lost on the way: the optimiser shrinks its step
    const LinearEvaluation e = p_.evaluate(*at);
    const int m = num_residuals();
    for (int i = 0; i < m; ++i) residuals[i] = p_.weight(i) * e.residuals(i);
    if (jacobians && jacobians[0]) {
      for (int i = 0; i < m; ++i) {
        for (int k = 0; k < n; ++k) jacobians[0][i * n + k] = p_.weight(i) * e.jacobian(i, k);
      }
    }
    return true;
  }

 private:
  const LinearProblem& p_;
  Follower& follower_;
};

// After each iteration: the accepted step becomes the reference; records the objective and
// every stiffness (the paper's Table 1) and reports progress.
class IterationRecorder : public ceres::IterationCallback {
 public:
  IterationRecorder(const LinearProblem& p, Follower& f, const Eigen::VectorXd& x,
                    LinearUpdateSummary* s)
      : p_(p), f_(f), x_(x), s_(s) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& it) override {
    if (!f_.accept(x_)) return ceres::SOLVER_ABORT;
    if (s_) {
      s_->history.push_back(it.cost);
      s_->theta_history.push_back(x_.array().exp());
    }
    if (p_.options.progress)
      p_.options.progress(it.iteration, it.cost, p_.evaluate(f_.reference()).max_error());
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const LinearProblem& p_;
  Follower& f_;
  const Eigen::VectorXd& x_;
  LinearUpdateSummary* s_;
};

// Least squares over the sets not held, from `start` (pairs known there), in the bounds.
ceres::TerminationType fit(const LinearProblem& p, TrackedPoint& point,
                           const std::vector<char>& held, LinearUpdateSummary* record) {
  const int n = p.size();
  std::vector<int> constant;
  for (int k = 0; k < n; ++k)
    if (held[static_cast<size_t>(k)]) constant.push_back(k);
  if (static_cast<int>(constant.size()) == n) return ceres::CONVERGENCE;
  Eigen::VectorXd x = point.x;
  Follower follower(p, point);
  ceres::Problem problem;
  problem.AddResidualBlock(new LinearCost(p, follower), nullptr, x.data());
  for (int k = 0; k < n; ++k) {
    problem.SetParameterLowerBound(x.data(), k, std::log(p.lower(k)));
    problem.SetParameterUpperBound(x.data(), k, std::log(p.upper(k)));
  }
  if (!constant.empty()) problem.SetManifold(x.data(), new ceres::SubsetManifold(n, constant));
  ceres::Solver::Options so;
  so.max_num_iterations = p.options.max_iterations;
  so.linear_solver_type = ceres::DENSE_QR;
  so.logging_type = ceres::SILENT;  // outcomes reach the user through the summary
  so.function_tolerance = 1e-12;
  so.gradient_tolerance = 1e-14;
  so.parameter_tolerance = 1e-10;
  so.update_state_every_iteration = true;
  IterationRecorder cb(p, follower, x, record);
  so.callbacks.push_back(&cb);
  ceres::Solver::Summary cs;
  ceres::Solve(so, &problem, &cs);
  if (record) record->iterations += std::max(0, static_cast<int>(cs.iterations.size()) - 1);
  point = follower.reference();
  return cs.termination_type;
}

// Each measured mode's relative frequency uncertainty: the stated frequency_std, or the mode's own
// (MeasuredModes::frequency_std) where wider.
Eigen::VectorXd mode_sigma(const MeasuredModes& measured, double frequency_std) {
  Eigen::VectorXd out = Eigen::VectorXd::Constant(measured.frequency_hz.size(), frequency_std);
  if (measured.frequency_std.size() == out.size()) out = out.cwiseMax(measured.frequency_std);
  return out;
}

// The problem with the bounds of the options (start x factors, then the named bounds).
LinearProblem make_problem(const StiffnessSets& sets, const model::Model& model,
                           const std::vector<std::string>& names,
                           const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                           const LinearUpdateOptions& options) {
  for (int k = 0; k < sets.size(); ++k) {
    if (!(sets.initial()(k) > 0)) {
      throw InputError(fmt::format("parameter set '{}': starting stiffness must be > 0", names[k]));
    }
  }
  LinearProblem p{sets, model, names, sensors, measured, options, sets.initial(), {}, {}, {}, {}};
  p.weight = options.frequency_std / mode_sigma(measured, options.frequency_std).array();
  p.lower = p.start * options.lower_factor;
  p.upper = p.start * options.upper_factor;
  for (const ParameterBound& b : options.bounds) {
    const auto it = std::find(names.begin(), names.end(), b.name);
    if (it == names.end()) {
      throw InputError(fmt::format("bounds of '{}': not one of the sets updated", b.name));
    }
    p.lower(it - names.begin()) = b.lower;
    p.upper(it - names.begin()) = b.upper;
  }
  return p;
}

// Sensitivity of each set at `at`; flat sets are marked.
void report_sensitivity(const LinearProblem& p, const LinearEvaluation& at,
                        LinearUpdateSummary& s) {
  const int n = p.size();
  s.parameters.resize(n);
  for (int k = 0; k < n; ++k) {
    ParameterReport& r = s.parameters[k];
    r.name = p.names[k];
    r.start = p.start(k);
    r.lower = p.lower(k);
    r.upper = p.upper(k);
    r.sensitivity = at.jacobian.rows() > 0 ? at.jacobian.col(k).cwiseAbs().maxCoeff() : 0.0;
    r.flat = r.sensitivity < p.options.flat_sensitivity;
  }
}

}  // namespace

namespace {

// The reduced chi-square that noise of the stated size exceeds in one fit in 6.3 (the one-sided
// 1-sigma point of the chi-square distribution over degrees_of_freedom > 0, divided by it: 1.72
// over 3).
double reduced_chi2_one_sigma(int degrees_of_freedom) {
  const boost::math::chi_squared chi2(degrees_of_freedom);
  return boost::math::quantile(chi2, 0.841344746) / degrees_of_freedom;
}

// The factor sqrt(1 + w (nu / (nu - 2) - 1)) by which standard deviations scaled by a reduced
// chi-square c > 1 over nu degrees of freedom are widened for Student's t, or 0 where nu <= 2
// (none can be stated). The share w grows from 0 at c = 1 (the scatter the stated noise gives
// on average) to 1 at its one-sided 1-sigma point (1.72 over 3 degrees of freedom): in between
// the stated noise is still a likely cause. Linearised (a normal error over the scale
// max(1, c) sigma^2, 3 degrees of freedom), noise as stated gives z-scores of RMS 0.93 without
// the t, 0.83 with it in full from c = 1 on (a sigma 1.73 times wider at c = 1.01 than at 0.99)
// and 0.86 with it in part; noise 1.5 to 5 times the stated 1.17-1.56 without, 0.93-0.99 in
// full and 0.98-1.03 in part.
double t_widening(double reduced_chi2, int degrees_of_freedom) {
  if (!(reduced_chi2 > 1)) return 1;
  const std::optional<double> t = student_t_variance(degrees_of_freedom);
  if (!t) return 0;
  const double w =
      std::clamp((reduced_chi2 - 1) / (reduced_chi2_one_sigma(degrees_of_freedom) - 1), 0.0, 1.0);
  return std::sqrt(1 + w * (*t - 1));
}

// The stated frequency uncertainty sf for the report, with each measured mode whose own sigma is
// wider (id(i) names mode i): "0.1 %, test mode 2's 0.427 %".
template <class Id>
std::string stated_noise(double sf, const Eigen::VectorXd& sigma, const Id& id) {
  std::vector<std::string> wider;
  for (Eigen::Index i = 0; i < sigma.size(); ++i)
    if (sigma(i) > sf * (1 + 1e-9))
      wider.push_back(fmt::format("test mode {}'s {:.3g} %", id(i), 100 * sigma(i)));
  if (wider.empty()) return fmt::format("{:.3g} %", 100 * sf);
  return fmt::format("{:.3g} %, {}", 100 * sf, fmt::join(wider, ", "));
}

// What the standard deviations of a scatter-set scale are, for the report: "rest on the
// scatter: widened by sqrt(2.21) and, as that scale is itself estimated from 3 degrees of
// freedom (Student's t), by 1.73", or why none is stated.
std::string scatter_widening(const LinearUpdateSummary& s) {
  const int nu = s.degrees_of_freedom;
  const char* plural = nu == 1 ? "" : "s";
  if (s.t_widening == 0)
    return fmt::format(
        "would rest on the scatter, but a scale estimated from {} degree{} of freedom leaves an "
        "error over its sigma with no finite standard deviation (Student's t needs more than 2): "
        "none is stated; add measured modes",
        nu, plural);
  const double full = std::sqrt(*student_t_variance(nu));
  if (s.t_widening >= full * (1 - 1e-12))
    return fmt::format(
        "rest on the scatter: widened by sqrt({:.3g}) and, as that scale is itself estimated "
        "from {} degree{} of freedom (Student's t), by {:.3g}",
        s.reduced_chi2, nu, plural, s.t_widening);
  const boost::math::chi_squared chi2(nu);
  return fmt::format(
      "rest on the scatter: widened by sqrt({:.3g}) and, as that scale is itself estimated from "
      "{} degree{} of freedom, by {:.3g} (Student's t's {:.3g} in part: noise of the stated size "
      "still scatters this much in one fit in {:.2g})",
      s.reduced_chi2, nu, plural, s.t_widening, full,
      1 / boost::math::cdf(boost::math::complement(chi2, s.reduced_chi2 * nu)));
}

// A singular value of the fitted sets' Jacobian with unit columns whose square is below this
// marks sets acting together: for two sets, a correlation of their sensitivities above 0.999.
constexpr double kCollinearSquared = 1e-3;

// The sensitivities of the fitted sets, J (columns d r / d ln theta of each), taken apart: the
// directions of ln theta the frequencies barely see (kCollinearSquared) and the sets each one
// moves (a share of at least a tenth of its largest), merged into groups acting together, and
// (J^T J)^+ without those directions (right for the combinations and for the sets outside the
// groups, where (J^T J)^-1 is rounding noise: +/- 1.11e+08 % for an Iwan element beside a
// spring on one degree of freedom).
struct SensitivityDirections {
  Eigen::MatrixXd inverse;               // (J^T J)^+, near-null directions dropped
  std::vector<std::vector<int>> groups;  // columns of J acting together, each ascending
  std::vector<int> unseen;               // near-null directions in each group
  int rank = 0;                          // combinations determined: columns - near-null
};

SensitivityDirections sensitivity_directions(const Eigen::MatrixXd& j) {
  const auto n = static_cast<int>(j.cols());
  SensitivityDirections out;
  const Eigen::VectorXd norm = j.colwise().norm().transpose();  // > 0: no flat set is fitted
  const Eigen::MatrixXd u = j * norm.cwiseInverse().asDiagonal();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(u, Eigen::ComputeFullV);
  const Eigen::VectorXd& sv = svd.singularValues();
  const Eigen::MatrixXd& v = svd.matrixV();
  Eigen::MatrixXd inverse = Eigen::MatrixXd::Zero(n, n);
  std::vector<int> root(static_cast<size_t>(n));
  for (int k = 0; k < n; ++k) root[static_cast<size_t>(k)] = k;
  const auto find = [&](int k) {
    while (root[static_cast<size_t>(k)] != k) k = root[static_cast<size_t>(k)];
    return k;
  };
  std::vector<int> unseen_at;  // a member of each near-null direction
  for (int i = 0; i < n; ++i) {
    const double s2 = i < sv.size() ? sv(i) * sv(i) : 0.0;
    if (s2 >= kCollinearSquared) {
      inverse += v.col(i) * v.col(i).transpose() / s2;
      ++out.rank;
      continue;
    }
    const double top = v.col(i).cwiseAbs().maxCoeff();
    int first = -1;
    for (int k = 0; k < n; ++k) {
      if (std::abs(v(k, i)) < 0.1 * top) continue;
      if (first < 0)
        first = k;
      else
        root[static_cast<size_t>(find(k))] = find(first);
    }
    unseen_at.push_back(first);
  }
  out.inverse = norm.cwiseInverse().asDiagonal() * inverse * norm.cwiseInverse().asDiagonal();
  std::vector<int> group_of(static_cast<size_t>(n), -1);
  for (int k = 0; k < n; ++k) {
    int& g = group_of[static_cast<size_t>(find(k))];
    if (g < 0) {
      g = static_cast<int>(out.groups.size());
      out.groups.emplace_back();
      out.unseen.push_back(0);
    }
    out.groups[static_cast<size_t>(g)].push_back(k);
  }
  for (const int k : unseen_at)
    ++out.unseen[static_cast<size_t>(group_of[static_cast<size_t>(find(k))])];
  // Only groups of two sets or more act together: a unit column is no combination of others
  // each below a tenth of its share unless ten or more of them sum to it.
  std::vector<std::vector<int>> groups;
  std::vector<int> unseen;
  for (size_t g = 0; g < out.groups.size(); ++g) {
    if (out.groups[g].size() < 2 || out.unseen[g] == 0) continue;
    groups.push_back(out.groups[g]);
    unseen.push_back(out.unseen[g]);
  }
  out.groups = std::move(groups);
  out.unseen = std::move(unseen);
  return out;
}

// The sets acting together in `d` (columns of J over the fitted sets `fitted`) recorded in
// s.collinear, each marked with the others in s.parameters, and one warning per group naming
// what the frequencies determine; `cov` is the covariance of ln theta over the fitted sets (empty
// where no sigma is stated).
void report_collinear(const std::vector<int>& fitted, const Eigen::VectorXd& theta,
                      const Eigen::MatrixXd& j, const SensitivityDirections& d,
                      const Eigen::MatrixXd& cov, LinearUpdateSummary& s) {
  for (size_t g = 0; g < d.groups.size(); ++g) {
    const std::vector<int>& cols = d.groups[g];
    CollinearSets c;
    std::vector<std::string> names;
    for (const int col : cols) {
      c.sets.push_back(fitted[static_cast<size_t>(col)]);
      names.push_back(s.parameters[fitted[static_cast<size_t>(col)]].name);
    }
    c.determined = static_cast<int>(cols.size()) - d.unseen[g];
    for (const int col : cols) {
      ParameterReport& r = s.parameters[fitted[static_cast<size_t>(col)]];
      r.relative_std.reset();
      for (const int other : cols)
        if (other != col)
          r.acts_with.push_back(s.parameters[fitted[static_cast<size_t>(other)]].name);
    }
    std::string what;
    if (cols.size() == 2) {
      // r sees theta_a g_a + theta_b g_b, g = d r / d theta; with g_b = weight g_a it sees
      // w = theta_a + weight theta_b alone.
      const int a = cols[0], b = cols[1];
      const int ka = fitted[static_cast<size_t>(a)], kb = fitted[static_cast<size_t>(b)];
      const ParameterReport& pa = s.parameters[ka];
      const ParameterReport& pb = s.parameters[kb];
      const double ta = theta(ka), tb = theta(kb);
      const Eigen::VectorXd ga = j.col(a) / ta, gb = j.col(b) / tb;
      c.weight = ga.dot(gb) / ga.squaredNorm();
      c.value = ta + c.weight * tb;
      c.correlation = std::abs(j.col(a).dot(j.col(b))) / (j.col(a).norm() * j.col(b).norm());
      if (cov.size() > 0) {
        const Eigen::Vector2d grad(ta / c.value, c.weight * tb / c.value);
        Eigen::Matrix2d sub;
        sub << cov(a, a), cov(a, b), cov(b, a), cov(b, b);
        const double var = grad.dot(sub * grad);
        if (var >= 0 && std::isfinite(var)) c.relative_std = std::sqrt(var);
      }
      const bool sum = std::abs(c.weight - 1) < 0.01;
      what = fmt::format(
          "their sensitivities are proportional (correlation {:.6f}), so the frequencies "
          "determine only {}, {} = {:.6g}{}, not each (the split {:.6g} and {:.6g} is where the "
          "fit stopped)",
          c.correlation, sum ? "their sum" : "one combination",
          sum ? fmt::format("{} + {}", pa.name, pb.name)
              : fmt::format("{} + {:.4g} {}", pa.name, c.weight, pb.name),
          c.value, c.relative_std ? fmt::format(" (+/- {:.3g} %)", 100 * *c.relative_std) : "", ta,
          tb);
    } else {
      what = fmt::format(
          "their sensitivities nearly repeat one another, so the frequencies determine only {} "
          "combination{} of the {}, not each",
          c.determined, c.determined == 1 ? "" : "s", cols.size());
    }
    const int hold = static_cast<int>(cols.size()) - c.determined;
    s.warnings.push_back(fmt::format(
        "{} act together: {}; hold {} of them at a value known otherwise (--hold NAME=VALUE) "
        "and fit the other{}",
        fmt::join(names, cols.size() == 2 ? " and " : ", "), what,
        hold == 1 ? "one" : std::to_string(hold), cols.size() - hold == 1 ? "" : "s"));
    s.collinear.push_back(std::move(c));
  }
}

// Sets the flat rule held at their start where the fit had driven them (not flat there, not
// held by the user), acting together with fitted sets: the fit drove one toward zero because
// another took up their common part, so the flat rule's hold fixes the split and the other's
// value rests on it. Two springs on one joint from kj 1.2e5 and kd 3e4 (truth: their sum 4e4):
// kd was driven to its lower bound, flat there, held at 3e4, and kj = 1e4 was stated
// identifiable at +/- 2.83 %. They are named as acting together as fitted ones are (kj's sigma
// dropped; the sum's is kj's, kd being held), over the fitted sets' covariance `cov` (empty:
// none stated).
void report_collinear_with_held_flat(const LinearProblem& p, const Eigen::VectorXd& theta,
                                     const LinearEvaluation& at, const std::vector<char>& held,
                                     const std::vector<int>& fitted, const Eigen::MatrixXd& cov,
                                     LinearUpdateSummary& s) {
  std::vector<int> with = fitted;
  for (int k = 0; k < p.size(); ++k) {
    const ParameterReport& r = s.parameters[k];
    if (held[static_cast<size_t>(k)] && !r.held_by_user && r.flat && r.drifted_to > 0 &&
        r.sensitivity >= p.options.flat_sensitivity)
      with.push_back(k);
  }
  if (with.size() == fitted.size() || fitted.empty()) return;
  const Eigen::MatrixXd jw = p.weighted_jacobian(at);
  Eigen::MatrixXd j(jw.rows(), static_cast<Eigen::Index>(with.size()));
  for (size_t c = 0; c < with.size(); ++c) j.col(c) = jw.col(with[c]);
  SensitivityDirections d = sensitivity_directions(j);
  // Only groups holding a set held here and a fitted one: groups of fitted sets alone are
  // reported already.
  const auto n_fitted = static_cast<int>(fitted.size());
  SensitivityDirections mixed;
  for (size_t g = 0; g < d.groups.size(); ++g) {
    const std::vector<int>& cols = d.groups[g];
    if (cols.front() < n_fitted && cols.back() >= n_fitted) {
      mixed.groups.push_back(cols);
      mixed.unseen.push_back(d.unseen[g]);
    }
  }
  if (mixed.groups.empty()) return;
  Eigen::MatrixXd c;
  if (cov.size() > 0) {
    c = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(with.size()),
                              static_cast<Eigen::Index>(with.size()));
    c.topLeftCorner(n_fitted, n_fitted) = cov;
  }
  const size_t first = s.collinear.size(), first_warning = s.warnings.size();
  report_collinear(with, theta, j, mixed, c, s);
  for (size_t g = first; g < s.collinear.size(); ++g) {
    std::vector<std::string> held_names;
    for (const int k : s.collinear[g].sets)
      if (held[static_cast<size_t>(k)]) held_names.push_back(s.parameters[k].name);
    s.warnings[first_warning + (g - first)] += fmt::format(
        "; {} was held at its start by the flat rule (the fit had driven it toward "
        "zero), which fixes the split",
        fmt::join(held_names, " and "));
  }
}

// Standard deviations of the fitted sets at the result (its Jacobian). Sets acting together
// (sensitivity_directions) have none, the combination they determine is named, and the degrees
// of freedom count the combinations determined. Where the frequencies of
// the least-squares fit `ls` scatter more than their stated uncertainty gives (reduced
// chi-square above 1; at the least-squares point: a rule that then moves to its tolerance adds
// errors on purpose, not scatter), the scale is the scatter's: the covariance is scaled by the
// reduced chi-square and, as that scale is itself estimated from nu = pairs - fitted degrees of
// freedom, widened by Student's t's variance nu / (nu - 2) (student_t_variance); none is stated
// where nu <= 2. Without the t, twoj's two joints fitted to five modes at three sensors with
// 0.5 % noise and the default 0.1 % gave z-scores of RMS 1.63 and 1.37 over 40 seeds (largest
// |z| 4.25): t over 3 degrees of freedom has a standard deviation of sqrt(3).
void report_uncertainty(const LinearProblem& p, const Eigen::VectorXd& theta,
                        const LinearEvaluation& at, const LinearEvaluation& ls,
                        const std::vector<char>& held, LinearUpdateSummary& s) {
  std::vector<int> fitted;
  s.collinear.clear();
  for (int k = 0; k < p.size(); ++k) {
    s.parameters[k].relative_std.reset();
    s.parameters[k].slope_std.reset();
    s.parameters[k].acts_with.clear();
    if (!held[static_cast<size_t>(k)] && !s.parameters[k].flat) fitted.push_back(k);
  }
  // Each row over its own mode's sigma: (J^T W^2 J)^-1 frequency_std^2 is the covariance.
  const Eigen::MatrixXd jw = p.weighted_jacobian(at);
  Eigen::MatrixXd j(jw.rows(), static_cast<Eigen::Index>(fitted.size()));
  for (size_t c = 0; c < fitted.size(); ++c) j.col(c) = jw.col(fitted[c]);
  const SensitivityDirections d =
      fitted.empty() ? SensitivityDirections{} : sensitivity_directions(j);
  const int pairs = static_cast<int>(ls.pairing.pairs.size());
  s.degrees_of_freedom = pairs - d.rank;
  const double sf = p.options.frequency_std;
  s.frequency_std = sf;
  s.mode_frequency_std = mode_sigma(p.measured, sf);
  s.chi2 = ls.weighted_squared_norm() / (sf * sf);
  s.reduced_chi2 = s.degrees_of_freedom > 0 ? s.chi2 / s.degrees_of_freedom : 0.0;
  s.sigma_from_scatter = s.degrees_of_freedom > 0 && s.reduced_chi2 > 1;
  s.t_widening = s.sigma_from_scatter ? t_widening(s.reduced_chi2, s.degrees_of_freedom) : 1.0;
  if (fitted.empty()) return;
  const std::string noise =
      stated_noise(sf, s.mode_frequency_std, [&](Eigen::Index i) { return p.measured.id(i); });
  // A model-form error only where noise of the stated size would rarely scatter so far (above
  // the one-sided 3-sigma point of the chi-square distribution: 4.45 over 4 degrees of freedom;
  // "above 1" was said for 7 of 20 fits of exact data with the stated noise).
  if (s.degrees_of_freedom > 0 && s.reduced_chi2 > reduced_chi2_limit(s.degrees_of_freedom)) {
    s.warnings.push_back(fmt::format(
        "the frequencies scatter beyond their stated uncertainty ({}): reduced chi-square "
        "{:.3g} over {} degrees of freedom (noise of that size stays below {:.3g} but once in 740 "
        "fits), so the model does not describe them to within it (model-form error); the "
        "standard deviations {}",
        noise, s.reduced_chi2, s.degrees_of_freedom, reduced_chi2_limit(s.degrees_of_freedom),
        scatter_widening(s)));
  }
  Eigen::MatrixXd cov;
  if (s.t_widening > 0) {
    const double scale =
        sf * sf * (s.sigma_from_scatter ? s.reduced_chi2 * s.t_widening * s.t_widening : 1.0);
    cov = d.inverse * scale;
    for (size_t c = 0; c < fitted.size(); ++c) {
      const double v = cov(c, c);
      if (v >= 0 && std::isfinite(v)) s.parameters[fitted[c]].relative_std = std::sqrt(v);
    }
  }
  report_collinear(fitted, theta, j, d, cov, s);
  report_collinear_with_held_flat(p, theta, at, held, fitted, cov, s);
  // (A sign-flipped sensor paired a 505 Hz test mode with a model mode then at 748 Hz, the one
  // pair for the one set, and the fit moved K_T 528-fold to match it exactly, "converged".)
  if (s.degrees_of_freedom == 0 && s.t_widening > 0) {
    // With no degree of freedom left a fit reaches every frequency unless a bound or the
    // pairs stop it: errors beyond 3 sigma at a pair are said (a reversed channel once left
    // 26.6 % with this warning saying the fit matched exactly).
    const double chi2 = ls.weighted_squared_norm() / (sf * sf);
    s.warnings.push_back(
        chi2 > 9.0 * pairs
            ? fmt::format(
                  "{} pair(s) for {} fitted set(s): no degree of freedom is left, and yet the fit "
                  "leaves errors up to {:.3g} % (chi-square {:.3g}): a bound stopped it, or no "
                  "stiffness meets these pairs; nothing checks the pairs or the model, so add "
                  "measured modes or sensors",
                  pairs, fitted.size(), 100 * ls.max_error(), chi2)
            : fmt::format(
                  "{} pair(s) for {} fitted set(s): no degree of freedom is left, so the fit "
                  "matches the frequencies exactly whatever the pairs and nothing checks them or "
                  "the model (the standard deviations only assume the stated {}); add "
                  "measured modes or sensors",
                  pairs, fitted.size(), noise));
  }
}

// How far the chi-square's profile lets a set go one way (d = +1 up, -1 down) from the result.
struct ProfileSide {
  bool checked = false;  // false: the set sits at its bound that way
  bool bounded = false;  // the profile rises by 9 (3 sigma) inside the bounds
  double sigma = 0;      // bounded: a third of the ln-distance to where it rises by 9
  double reached = 0;    // not bounded: the farthest value tried, its rise and sensitivity
  double rise = 0;
  double sensitivity = 0;
  bool lost = false;  // not bounded: beyond `reached` the pairs could not be followed
};

// The profile of set k one way: k moved, the other fitted sets fitted again at each value
// (pairs followed by shape), its chi-square rise in units of `scale` (the stated variance, or the
// scatter's). From 3 local standard deviations outward, each step up to 3 times the last, until
// it rises by 9 (the distance interpolated in the square root of the rise, which a straight line
// makes linear) or meets the bound (at most 8 steps). A rise within 5 % of a straight line's
// where it is first looked at (at 3 sigma, or the bound if nearer) is taken as the line's. A
// step whose pairs cannot be followed or change counts as the end: the frequencies leave it.
ProfileSide profile_side(const LinearProblem& p, const TrackedPoint& point, int k, int d,
                         double local, const std::vector<char>& held, double base, double scale) {
  ProfileSide side;
  const double x0 = point.x(k);
  const double room = d > 0 ? std::log(p.upper(k)) - x0 : x0 - std::log(p.lower(k));
  if (!(room > 1e-9)) return side;
  side.checked = true;
  std::vector<char> with_k = held;
  with_k[static_cast<size_t>(k)] = 1;
  const size_t pairs = p.evaluate(point).pairing.pairs.size();
  TrackedPoint from = point;
  double t_lo = 0, r_lo = 0;
  double t = 3 * local;
  for (int step = 0; step < 8; ++step) {
    const bool last = t >= room;
    if (last) t = room;
    Eigen::VectorXd x = from.x;
    x(k) = x0 + d * t;
    std::optional<TrackedPoint> q =
        p.move(from, x, std::max(4, static_cast<int>(std::ceil(4 * (t - t_lo)))));
    std::optional<LinearEvaluation> e;
    if (q) {
      fit(p, *q, with_k, nullptr);
      e = p.evaluate(*q);
    }
    if (!e || e->pairing.pairs.size() != pairs) {
      // At 3 sigma as the local slope has it (as before); farther out nothing is known there.
      side.bounded = step == 0;
      side.sigma = local;
      side.lost = true;
      return side;
    }
    const double rise = std::max(0.0, (e->weighted_squared_norm() - base) / scale);
    if (rise >= 9) {
      const double t9 =
          t_lo + (3 - std::sqrt(r_lo)) / (std::sqrt(rise) - std::sqrt(r_lo)) * (t - t_lo);
      side.bounded = true;
      side.sigma = std::max(local, t9 / 3);
      return side;
    }
    if (step == 0 && std::sqrt(rise) >= 0.95 * t / local) {
      side.bounded = true;
      side.sigma = std::max(local, t / std::sqrt(rise));
      return side;
    }
    side.reached = std::exp(x(k));
    side.rise = rise;
    side.sensitivity = e->jacobian.rows() > 0 ? e->jacobian.col(k).cwiseAbs().maxCoeff() : 0.0;
    if (last) return side;
    t_lo = t;
    r_lo = rise;
    from = std::move(*q);
    t *= std::clamp(1.1 * 3 / std::sqrt(std::max(rise, 0.09)), 1.25, 3.0);
  }
  return side;
}

// Fitted sets the frequencies bound from one side only, and standard deviations the chi-square
// does not bear out. A stiff set's sensitivity dies away as it stiffens, so the frequencies may
// bound it from below and not from above, and the local slope (J at the result) then gives a
// standard deviation too small on that side: kflat, started at 3e7 (truth 1e10) with 0.1 % noise,
// stopped at 5.03e7 and was stated at +/- 39.6 %, the truth 13 of those sigmas away. Each set with
// a standard deviation has its profile walked each way (profile_side) to where the chi-square
// rises by 9, 3 standard deviations; a third of the farther is stated where it is wider than the
// local slope's. Before, a rise of 4 at 3 local sigmas passed (a straight line gives 9): the two
// chains' kflat made at 3e7 with 0.2 % noise was stated in 41 of 400 seeds, z-scores RMS 1.79 and
// 4 beyond 3 (to -4.84), each where the fit had come out low, where the slope is steep and the
// side above flattens. Where the bound comes first the set is bounded from one side only: no
// standard deviation, and the warning says how little the chi-square rose.
void report_one_sided(const LinearProblem& p, const TrackedPoint& point, const LinearEvaluation& at,
                      const std::vector<char>& held, LinearUpdateSummary& s) {
  const double sf = p.options.frequency_std;
  const double scale =
      sf * sf * (s.sigma_from_scatter ? s.reduced_chi2 * s.t_widening * s.t_widening : 1.0);
  const double base = at.weighted_squared_norm();
  for (int k = 0; k < p.size(); ++k) {
    ParameterReport& r = s.parameters[k];
    if (!r.relative_std || !(*r.relative_std > 0)) continue;
    const double local = *r.relative_std;
    double sigma = local;
    for (const int d : {1, -1}) {
      const ProfileSide side = profile_side(p, point, k, d, local, held, base, scale);
      if (!side.checked) continue;
      if (side.bounded) {
        sigma = std::max(sigma, side.sigma);
        continue;
      }
      r.one_sided = d;
      const double moved = std::abs(std::log(side.reached) - point.x(k)) / local;
      s.warnings.push_back(fmt::format(
          "{}: the frequencies bound it from {} only: moved {} to {:.6g} ({:.3g} standard "
          "deviations of the local slope{}), the other sets fitted again, the chi-square rises by "
          "only {:.3g} where 9 marks 3 standard deviations{} (sensitivity {:.3g} at the result, "
          "{:.3g} there), so its +/- {:.3g} % would understate how far it may be, and none is "
          "stated; hold it at a value known otherwise (--hold {}=VALUE)",
          r.name, d > 0 ? "below" : "above", d > 0 ? "up" : "down", side.reached, moved,
          std::abs(std::log(side.reached) - std::log(d > 0 ? p.upper(k) : p.lower(k))) < 1e-9
              ? ", its bound"
              : "",
          side.rise, side.lost ? ", and beyond it the pairs cannot be followed" : "", r.sensitivity,
          side.sensitivity, 100 * local, r.name));
      r.relative_std.reset();
      break;
    }
    if (r.relative_std && sigma > local * (1 + 1e-3)) {
      r.relative_std = sigma;
      r.slope_std = local;
    }
  }
}

// Within the tolerance: every pair of `at` kept, every paired error at most the tolerance.
auto within_tolerance(const LinearProblem& p, const LinearEvaluation& at) {
  return [&p, pairs = at.pairing.pairs.size()](const LinearEvaluation& e) {
    return e.pairing.pairs.size() == pairs && e.max_error() <= p.options.tolerance;
  };
}

// The paper's rule: the smallest theta_k with the others fitted and every error within the
// tolerance; `point` moves to it.
void smallest_rule(const LinearProblem& p, int k, std::vector<char> held, TrackedPoint& point,
                   LinearUpdateSummary& s) {
  const auto within = within_tolerance(p, p.evaluate(point));
  if (!within(p.evaluate(point))) {
    s.tolerance_met = false;
    s.warnings.push_back(
        fmt::format("the tolerance {:.3g} % cannot be met: the least-squares fit leaves a largest "
                    "frequency error of {:.3g} %; kept the least-squares result",
                    100 * p.options.tolerance, 100 * p.evaluate(point).max_error()));
    return;
  }
  held[static_cast<size_t>(k)] = 1;
  // feasible(v): fit the others at theta_k = v from the last feasible point.
  TrackedPoint best = point;
  auto feasible = [&](double v) {
    Eigen::VectorXd x = best.x;
    x(k) = v;
    std::optional<TrackedPoint> trial = p.move(best, x);
    if (!trial) return false;
    fit(p, *trial, held, nullptr);
    const LinearEvaluation e = p.evaluate(*trial);
    if (!within(e)) return false;
    best = std::move(*trial);
    s.history.push_back(e.cost());
    s.theta_history.push_back(best.x.array().exp());
    return true;
  };
  double hi = point.x(k), lo = std::log(p.lower(k));
  if (feasible(lo)) {
    s.warnings.push_back(fmt::format(
        "{}: every value down to its lower bound {:.6g} keeps the errors within {:.3g} %: the "
        "frequencies do not bound it from below, and the result is that bound",
        p.names[k], p.lower(k), 100 * p.options.tolerance));
  } else {
    // ln theta to 1e-3: theta_m within 0.1 % of the smallest feasible value.
    for (int it = 0; it < 60 && hi - lo > 1e-3; ++it) {
      const double mid = 0.5 * (lo + hi);
      (feasible(mid) ? hi : lo) = mid;
    }
  }
  point = best;
  s.parameters[k].smallest_within_tolerance = std::exp(point.x(k));
}

// The smallest stiffness within the tolerance for each flat set, the others held; a set that
// meets it down to its lower bound stays where it is.
void smallest_flat(const LinearProblem& p, TrackedPoint& point, LinearUpdateSummary& s) {
  const auto within = within_tolerance(p, p.evaluate(point));
  for (int k = 0; k < p.size(); ++k) {
    if (!s.parameters[k].flat || s.parameters[k].held_by_user) continue;
    auto at = [&](double lx) -> std::optional<TrackedPoint> {
      Eigen::VectorXd x = point.x;
      x(k) = lx;
      std::optional<TrackedPoint> q = p.move(point, x);
      if (!q || !within(p.evaluate(*q))) return std::nullopt;
      return q;
    };
    if (!within(p.evaluate(point))) continue;
    double hi = point.x(k), lo = std::log(p.lower(k));
    if (at(lo)) {
      s.warnings.push_back(fmt::format(
          "{}: every value down to its lower bound {:.6g} keeps the errors within {:.3g} %: "
          "held at {:.6g}",
          p.names[k], p.lower(k), 100 * p.options.tolerance, std::exp(point.x(k))));
      continue;
    }
    for (int it = 0; it < 40 && hi - lo > 1e-4; ++it) {
      const double mid = 0.5 * (lo + hi);
      (at(mid) ? hi : lo) = mid;
    }
    if (std::optional<TrackedPoint> q = at(hi)) point = std::move(*q);
    s.parameters[k].smallest_within_tolerance = std::exp(point.x(k));
  }
}

// Warns of every set that ends at a bound.
void warn_bounds(const LinearProblem& p, const Eigen::VectorXd& theta, LinearUpdateSummary& s) {
  for (int k = 0; k < p.size(); ++k) {
    ParameterReport& r = s.parameters[k];
    const double lx = std::log(theta(k));
    r.at_bound = 0;
    if (lx <= std::log(p.lower(k)) + 1e-6) r.at_bound = -1;
    if (lx >= std::log(p.upper(k)) - 1e-6) r.at_bound = 1;
    if (r.at_bound != 0) {
      s.warnings.push_back(fmt::format(
          "{} ends at its {} bound {:.6g}: widen the bounds or hold it", r.name,
          r.at_bound < 0 ? "lower" : "upper", r.at_bound < 0 ? p.lower(k) : p.upper(k)));
    }
  }
}

// One warning naming the model modes the sensors cannot tell apart among the paired ones and
// their neighbours (modes up to 1.5 x the highest measured frequency).
void warn_aliased(const LinearProblem& p, const LinearEvaluation& at, LinearUpdateSummary& s) {
  const double f_top = 1.5 * p.measured.frequency_hz.maxCoeff();
  Eigen::Index count = 0;
  while (count < at.all_model_frequency_hz.size() && at.all_model_frequency_hz(count) <= f_top)
    ++count;
  std::vector<char> paired(static_cast<size_t>(at.all_model_frequency_hz.size()), 0);
  for (const ModePair& q : at.pairing.pairs) paired[static_cast<size_t>(q.model)] = 1;
  std::vector<char> hidden(paired.size(), 0);
  for (int j : at.hidden) hidden[static_cast<size_t>(j)] = 1;
  std::vector<std::string> pairs;
  for (const AliasedModes& a :
       aliased_modes(at.model_at_sensors.leftCols(count), p.options.alias_mac)) {
    if (hidden[a.a] || hidden[a.b] || !(paired[a.a] || paired[a.b])) continue;
    pairs.push_back(fmt::format("{} ({:.4g} Hz) and {} ({:.4g} Hz), auto-MAC {:.3f}", a.a + 1,
                                at.all_model_frequency_hz(a.a), a.b + 1,
                                at.all_model_frequency_hz(a.b), a.mac));
  }
  if (pairs.empty()) return;
  s.warnings.push_back(fmt::format(
      "the sensors cannot tell these model modes apart by shape: {}; their pairs rest on "
      "frequency and on following each mode's full shape, so add sensors that see them apart "
      "for a MAC that confirms them",
      fmt::join(pairs, "; ")));
}

// One-at-a-time sweeps around the result, every pair followed by its full shape from the result
// on a grid eight times finer than the sweep's.
void sweeps(const LinearProblem& p, const TrackedPoint& result, LinearUpdateSummary& s) {
  const LinearUpdateOptions& o = p.options;
  const int m = static_cast<int>(p.measured.frequency_hz.size());
  const int n = o.sweep_points;
  std::vector<double> d(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) d[i] = -o.sweep_decades + 2.0 * o.sweep_decades * i / (n - 1);
  // The start point is the sweep point nearest the result (factor 1).
  int mid = 0;
  for (int i = 1; i < n; ++i)
    if (std::abs(d[i]) < std::abs(d[mid])) mid = i;
  for (int k = 0; k < p.size(); ++k) {
    ParameterReport& r = s.parameters[k];
    r.value = std::exp(result.x(k));
    r.sweep_factor.assign(static_cast<size_t>(n), 0.0);
    r.sweep_rms.assign(static_cast<size_t>(n), std::nullopt);
    r.sweep_errors.assign(static_cast<size_t>(n), std::vector<std::optional<double>>(m));
    for (int i = 0; i < n; ++i) r.sweep_factor[i] = std::pow(10.0, d[i]);
  }
  // Outward from the result in each direction, reached along the sweep's own line. Each set's
  // two walks are independent of every other (pure eigen-solves; each writes its own points),
  // so they run side by side: the sweeps were 71 % of an update of the example beam's four sets
  // (256 eigen-solves of its 353 DOFs), and the numbers do not depend on the order.
  const auto walk = [&](int k, int from, int to, int step) {
    ParameterReport& r = s.parameters[k];
    std::optional<TrackedPoint> at = result;
    double last = 0;  // decades from the result
    for (int i = from; i != to + step; i += step) {
      if (!at) break;
      Eigen::VectorXd x = result.x;
      x(k) += d[i] * std::log(10.0);
      const int substeps = std::max(
          1,
          static_cast<int>(std::ceil(8 * std::abs(d[i] - last) * (n - 1) / (2 * o.sweep_decades))));
      at = p.move(*at, x, substeps);
      last = d[i];
      if (!at) break;
      const LinearEvaluation e = p.evaluate(*at);
      for (const ModePair& q : e.pairing.pairs)
        r.sweep_errors[i][static_cast<size_t>(q.measured)] = e.residuals(q.measured);
      if (!e.pairing.pairs.empty()) r.sweep_rms[i] = rms_of(e);
    }
  };
  parallel_for(
      2 * static_cast<size_t>(p.size()), 0, [] { return 0; },
      [&](size_t job, int) {
        const int k = static_cast<int>(job / 2);
        if (job % 2 == 0)
          walk(k, mid, n - 1, 1);
        else if (mid > 0)
          walk(k, mid - 1, 0, -1);
      });
}

LinearUpdateStatus status_of(ceres::TerminationType tt) {
  if (tt == ceres::CONVERGENCE) return LinearUpdateStatus::kConverged;
  if (tt == ceres::NO_CONVERGENCE) return LinearUpdateStatus::kIterationLimit;
  return LinearUpdateStatus::kFailed;
}

std::string pair_text(const LinearEvaluation& e, int i) {
  const int j = e.pairing.model_for(i);
  if (j < 0) return "unpaired";
  return fmt::format("model mode {} ({:.5g} Hz, MAC {:.3f})", j + 1, e.all_model_frequency_hz(j),
                     e.mac(i, j));
}

// At most this many candidate pairings are fitted from the start: each is a whole fit
// (seconds on a thousand-DOF model), and more guesses than this say the sensors do not see
// the modes apart.
constexpr size_t kMaxPairings = 16;

// The pairings to try where the rules pair `at` (made afresh at `point`) by a guess: every
// combination of one candidate for each tie (each a swap, so the pairs stay one to one), or
// for the first `ties` ties alone; else `point`. At the start every tie is tried: a later tie
// is met only once an earlier guess is made, and trying the first tie's candidates alone
// left a fit "converged" on a wrong guess of the second. At a fit's result the first alone
// (each candidate there is a fit of its own, within each start's fit).
std::vector<TrackedPoint> candidate_pairings(const TrackedPoint& point, const LinearEvaluation& at,
                                             size_t ties) {
  std::vector<TrackedPoint> out{point};
  for (size_t k = 0; k < at.ties.size() && k < ties; ++k) {
    const PairingTie& tie = at.ties[k];
    std::vector<TrackedPoint> next;
    const size_t i = static_cast<size_t>(tie.measured);
    for (const TrackedPoint& base : out)
      for (int c : tie.candidates) {
        TrackedPoint t = base;
        for (int& col : t.columns)
          if (col == c) col = base.columns[i];
        t.columns[i] = c;
        if (std::none_of(next.begin(), next.end(),
                         [&](const TrackedPoint& o) { return o.columns == t.columns; }))
          next.push_back(std::move(t));
      }
    out = std::move(next);
  }
  return out;
}

// A warning about one measured mode's pair: a mode followed by its shape to a model mode whose
// MAC at the result is below the threshold. update_linear() keeps it unless the line on the
// pairs the shapes do not confirm (LinearUpdateSummary::unconfirmed) already names that mode.
struct PairWarning {
  int measured = -1;  // the measured mode's row
  std::string text;
};

// What differs between two fitted pairings that the data cannot tell apart: each measured mode
// paired with another model mode (by shape), named with its partner at each result (its own
// numbering there), the sets that differ between the results, and the costs.
std::string differing_pairs(const LinearProblem& p, const TrackedPoint& a, double cost_a,
                            const TrackedPoint& b, double cost_b) {
  const LinearEvaluation ea = p.evaluate(a), eb = p.evaluate(b);
  const auto partner = [&](const LinearEvaluation& e, int i) {
    const int j = e.pairing.model_for(i);
    if (j < 0) return std::string("unpaired");
    const std::optional<double> mac = e.pair_mac(i);
    return fmt::format("model mode {} ({:.5g} Hz{})", j + 1, e.all_model_frequency_hz(j),
                       mac ? fmt::format(", MAC {:.3f}", *mac) : "");
  };
  std::vector<std::string> modes, sets_a, sets_b;
  for (size_t i = 0; i < a.columns.size() && i < b.columns.size(); ++i) {
    if (same_partners(p.model.mass, a.modes, {a.columns[i]}, b.modes, {b.columns[i]})) continue;
    const int k = static_cast<int>(i);
    std::string between;
    if (a.columns[i] >= 0 && b.columns[i] >= 0) {
      const double c =
          a.modes.shapes.col(a.columns[i]).dot(p.model.mass * b.modes.shapes.col(b.columns[i]));
      between = fmt::format(" (mass-weighted MAC {:.2f} between the two)", c * c);
    }
    modes.push_back(fmt::format(
        "test mode {} ({:.5g} Hz) with {} at one and with {} at the other{}", p.measured.id(k),
        p.measured.frequency_hz(k), partner(ea, k), partner(eb, k), between));
  }
  for (int k = 0; k < p.size(); ++k) {
    if (std::abs(a.x(k) - b.x(k)) < 0.01) continue;
    sets_a.push_back(fmt::format("{} {:.4g}", p.names[static_cast<size_t>(k)], std::exp(a.x(k))));
    sets_b.push_back(fmt::format("{} {:.4g}", p.names[static_cast<size_t>(k)], std::exp(b.x(k))));
  }
  return fmt::format(
      "two results pair {}{}, and leave costs {:.4g} and {:.4g}, which the data cannot tell "
      "apart (less than 9 apart in chi-square units of the stated frequency noise)",
      fmt::join(modes, "; "),
      sets_a.empty() ? std::string()
                     : fmt::format(" (the first at {}, the second at {})", fmt::join(sets_a, ", "),
                                   fmt::join(sets_b, ", ")),
      cost_a, cost_b);
}

// The outcome of settle().
struct Settled {
  TrackedPoint point;
  LinearUpdateSummary record;           // history, iterations, warnings
  std::vector<PairWarning> weak_pairs;  // pairs followed below the MAC threshold at the result
  LinearUpdateStatus status = LinearUpdateStatus::kFailed;
  double cost = 0;
  int rounds = 0;
  std::string ambiguity;  // non-empty: the pairs cannot be decided
  // With an ambiguity: the results that pair some mode otherwise and fit as well as `point`.
  std::vector<TrackedPoint> rivals;
  LinearEvaluation fresh_end;
};

// Least squares with pairs followed by shape from `point`. At its result the pairs are made
// afresh by the rules; where they differ, or where the sensors cannot tell two candidates
// apart (a twisting mode veering with a bending mode), each candidate pairing is fitted too
// and the data decide: the lowest cost wins when it is lower by at least 9 (3 sigma) in
// chi-square units, 2 (c_other - c_best) / sigma_f^2; otherwise the pairs cannot be decided.
Settled settle(const LinearProblem& p, TrackedPoint point, const std::vector<char>& held) {
  Settled out;
  const MeasuredModes& measured = p.measured;
  std::vector<std::vector<int>> tried{point.columns};
  out.status = status_of(fit(p, point, held, &out.record));
  out.rounds = 1;
  // The fit renumbers the modes where they cross: the candidates below are compared with the
  // followed pairs at the fit's result, not at its start (at the start's numbering the example
  // beam's followed pairs came back as a candidate, fitted again as "the sensors' pairs").
  tried.push_back(point.columns);
  for (int check = 0; check < 4; ++check) {
    TrackedPoint again = p.fresh(point.x, out.fresh_end);
    const LinearEvaluation& fresh_end = out.fresh_end;
    if (again.columns == point.columns && fresh_end.ambiguity.empty()) break;
    // A pairing that leaves a followed mode unpaired would win on cost by dropping a residual:
    // it is not a candidate; the weak pair is said instead.
    const auto pairs_of = [](const TrackedPoint& t) {
      return std::count_if(t.columns.begin(), t.columns.end(), [](int c) { return c >= 0; });
    };
    std::vector<TrackedPoint> candidates;
    for (TrackedPoint& c : candidate_pairings(again, fresh_end, 1)) {
      if (std::find(tried.begin(), tried.end(), c.columns) != tried.end()) continue;
      tried.push_back(c.columns);
      if (pairs_of(c) < pairs_of(point)) {
        const LinearEvaluation followed = p.evaluate(point);
        for (size_t i = 0; i < c.columns.size(); ++i) {
          if (c.columns[i] >= 0 || point.columns[i] < 0) continue;
          out.weak_pairs.push_back(
              {static_cast<int>(i),
               fmt::format("test mode {} ({:.5g} Hz) is followed by its shape to {}, below the "
                           "MAC threshold at the result: check its measured shape",
                           measured.id(static_cast<Eigen::Index>(i)),
                           measured.frequency_hz(static_cast<Eigen::Index>(i)),
                           pair_text(followed, static_cast<int>(i)))});
        }
        continue;
      }
      candidates.push_back(std::move(c));
    }
    if (candidates.empty() && fresh_end.ambiguity.empty()) break;
    // The followed pairs and each candidate, fitted; the lowest cost wins unless a result that
    // pairs some measured mode with another model mode (by shape: a mode crossing between two
    // results renumbers the modes, and the example beam's sixth bending mode, model mode 9
    // with spring.rz at 1e5 and 10 with rz at 0.1, was taken for two pairings, "cannot be
    // decided" in 3 of 12 seeds of 0.1 % noise) fits within 9 chi-square units of it.
    struct Tried {
      TrackedPoint point;
      double cost = 0;
      ceres::TerminationType tt = ceres::CONVERGENCE;
      LinearUpdateSummary record;
    };
    std::vector<Tried> results;
    results.push_back({point, p.evaluate(point).cost(), ceres::CONVERGENCE, {}});
    for (TrackedPoint& c : candidates) {
      Tried t{std::move(c), 0, ceres::CONVERGENCE, {}};
      t.tt = fit(p, t.point, held, &t.record);
      ++out.rounds;
      t.cost = p.evaluate(t.point).cost();
      results.push_back(std::move(t));
    }
    size_t best = 0;
    for (size_t k = 1; k < results.size(); ++k)
      if (results[k].cost < results[best].cost) best = k;
    // The results that pair some measured mode otherwise than the best (by shape), compared
    // with it once each; the runner is the lowest of them.
    std::vector<size_t> others;
    std::optional<size_t> runner;
    for (size_t k = 0; k < results.size(); ++k) {
      if (k == best || same_partners(p.model.mass, results[k].point.modes, results[k].point.columns,
                                     results[best].point.modes, results[best].point.columns))
        continue;
      others.push_back(k);
      if (!runner || results[k].cost < results[*runner].cost) runner = k;
    }
    const double sf2 = p.options.frequency_std * p.options.frequency_std;
    if (runner && !(2 * (results[*runner].cost - results[best].cost) / sf2 >= 9)) {
      out.ambiguity = fmt::format(
          "{}{}", fresh_end.ambiguity.empty() ? "" : fresh_end.ambiguity + "; fitted each way, ",
          differing_pairs(p, results[best].point, results[best].cost, results[*runner].point,
                          results[*runner].cost));
      for (const size_t k : others)
        if (2 * (results[k].cost - results[best].cost) / sf2 < 9)
          out.rivals.push_back(results[k].point);
      if (best > 0) point = std::move(results[best].point);
      break;
    }
    if (best == 0) {
      // The pairs followed by shape fit decisively better than the sensors' own: kept, said.
      if (runner) {
        std::vector<std::string> costs;
        for (size_t k = 0; k < results.size(); ++k)
          costs.push_back(fmt::format("{:.4g}{}", results[k].cost, k == 0 ? " as followed" : ""));
        out.record.warnings.push_back(fmt::format(
            "at the result the sensors alone would pair differently ({}), but those pairs fit "
            "worse (costs {}): kept the pairs followed by shape",
            fresh_end.ambiguity.empty() ? "MAC and frequency" : fresh_end.ambiguity,
            fmt::join(costs, ", ")));
      }
      break;
    }
    Tried& w = results[best];
    out.status = status_of(w.tt);
    out.record.history.insert(out.record.history.end(), w.record.history.begin(),
                              w.record.history.end());
    out.record.theta_history.insert(out.record.theta_history.end(), w.record.theta_history.begin(),
                                    w.record.theta_history.end());
    out.record.iterations += w.record.iterations;
    point = std::move(w.point);
    tried.push_back(point.columns);
  }
  out.point = std::move(point);
  out.cost = p.evaluate(out.point).cost();
  return out;
}

// The pairs whose model partner changed its shape along the fit (mass-weighted MAC below 0.5
// between the start's partner and the result's: another mode took its place, through a
// veering or a new pairing) and whose MAC at the result cannot confirm the new partner (a
// shape at fewer than two sensors, or below the threshold): their measured rows, each with a
// line on it.
std::vector<std::pair<int, std::string>> unconfirmed_changes(
    const Eigen::SparseMatrix<double>& mass, const TrackedPoint& start, const TrackedPoint& end,
    const LinearEvaluation& at_end, const MeasuredModes& measured, double mac_threshold) {
  std::vector<std::pair<int, std::string>> out;
  for (size_t i = 0; i < end.columns.size() && i < start.columns.size(); ++i) {
    const int a = start.columns[i], b = end.columns[i];
    if (a < 0 || b < 0) continue;
    const Eigen::VectorXd mb = mass * end.modes.shapes.col(b);
    const double c = start.modes.shapes.col(a).dot(mb);
    const std::optional<double> mac = at_end.pair_mac(static_cast<Eigen::Index>(i));
    if (c * c >= 0.5 || (mac && *mac >= mac_threshold)) continue;
    out.emplace_back(
        static_cast<int>(i),
        fmt::format(
            "test mode {} ({:.5g} Hz) from model mode {} to {} (mass-weighted MAC {:.2f} "
            "between them; {})",
            measured.id(static_cast<Eigen::Index>(i)),
            measured.frequency_hz(static_cast<Eigen::Index>(i)), a + 1, b + 1, c * c,
            mac ? fmt::format("MAC {:.2f} at the sensors", *mac) : "no shape at two sensors"));
  }
  return out;
}

// A fitted set that only pairs the sensors cannot confirm see (their partners changed along
// the fit) is not identified: the fit may have moved it until another mode sat at a measured
// frequency. With one sensor, spring.rz went from 100 to 2129 N m/rad that way (a twisting
// mode tuned onto a measured frequency), "converged" with a 7 % uncertainty, and the truth,
// 100, fitted as well. Returns why the update stops, or ""; where every fitted set is also
// seen by confirmed pairs the result stands and *warning says which pairs changed.
std::string unconfirmed_sets(const LinearProblem& p, const Eigen::SparseMatrix<double>& mass,
                             const TrackedPoint& start, const TrackedPoint& end,
                             const MeasuredModes& measured, const LinearUpdateOptions& options,
                             const std::vector<char>& held, const std::vector<std::string>& names,
                             std::string* warning) {
  const LinearEvaluation at = p.evaluate(end);
  const auto changes = unconfirmed_changes(mass, start, end, at, measured, options.mac_threshold);
  if (changes.empty()) return "";
  std::vector<std::string> lines, blind;
  std::vector<char> changed(static_cast<size_t>(at.residuals.size()), 0);
  for (const auto& [i, line] : changes) {
    lines.push_back(line);
    changed[static_cast<size_t>(i)] = 1;
  }
  // Seen by the changed pairs and by no other. A set no pair sees (kflat: every sensitivity
  // below flat_sensitivity) is flat, held by the flat rule whatever the pairs: naming it here
  // refused a fit that had found ka and kb exactly.
  for (int k = 0; k < p.size(); ++k) {
    if (held[static_cast<size_t>(k)]) continue;
    double seen = 0, seen_changed = 0;
    for (const ModePair& pr : at.pairing.pairs) {
      double& by = changed[static_cast<size_t>(pr.measured)] ? seen_changed : seen;
      by = std::max(by, std::abs(at.jacobian(pr.measured, k)));
    }
    if (seen < options.flat_sensitivity && seen_changed >= options.flat_sensitivity)
      blind.push_back(names[static_cast<size_t>(k)]);
  }
  const std::string what = fmt::format(
      "the partners of {} changed their shape along the fit (another mode took their place, "
      "through a veering or a new pairing) and the sensors cannot confirm the new ones",
      fmt::join(lines, "; "));
  if (blind.empty()) {
    *warning = what + "; every fitted set is also seen by confirmed pairs, so the result stands";
    return "";
  }
  return fmt::format(
      "{}; {} only these pairs see, so the fit may have moved it until another mode sat at a "
      "measured frequency: add sensors that see the modes apart, or hold it (--hold NAME)",
      what, fmt::join(blind, " and "));
}

// Where the channels with measured entries other than `reversed` are at most one more than
// them, the clause saying that reversing those instead is the same (MAC ignores a shape's
// overall sign: with three of five channels mounted reversed the checks name the other two,
// and either fix fits alike); else "".
std::string same_as_the_others(const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                               const std::vector<int>& reversed) {
  std::vector<std::string> others;
  for (Eigen::Index k = 0; k < measured.shapes.rows(); ++k)
    if ((measured.shapes.row(k).array().abs() > 0.0).any() &&
        std::find(reversed.begin(), reversed.end(), static_cast<int>(k)) == reversed.end())
      others.push_back(sensors[static_cast<size_t>(k)].channel);
  if (others.empty() || others.size() > reversed.size() + 1) return "";
  return fmt::format(
      " (or, as a shape's sign as a whole is arbitrary, the same: {} reversed instead)",
      fmt::join(others, ", "));
}

// What is wrong with the measured shapes against the model at the start (shape_checks.h), or "".
std::string shape_problem(const LinearEvaluation& start, const std::vector<Sensor>& sensors,
                          const MeasuredModes& measured, const LinearUpdateOptions& options) {
  std::vector<std::string> ids;
  for (Eigen::Index i = 0; i < measured.frequency_hz.size(); ++i) ids.push_back(measured.id(i));
  if (std::string why =
          phaseless_shapes(measured.shapes, measured.frequency_hz, start.model_at_sensors,
                           start.all_model_frequency_hz, ids, options.frequency_window);
      !why.empty())
    return why;
  if (options.trust_signs) return "";
  const SignCheck c =
      check_channel_signs(measured.shapes, measured.frequency_hz, start.model_at_sensors,
                          start.all_model_frequency_hz, start.hidden, options.frequency_window);
  if (c.channels.empty()) return "";
  std::vector<std::string> names, signs;
  for (const int k : c.channels) {
    const Sensor& r = sensors[static_cast<size_t>(k)];
    names.push_back(r.channel);
    signs.push_back(fmt::format("{} sign {:+g}", r.channel, -r.sign));
  }
  const std::string which = fmt::format("{}", fmt::join(names, " and "));
  const bool one = names.size() == 1;
  return fmt::format(
      "channel{} {} read{} the model reversed: as given, {} of {} measured modes (with entries at "
      "three sensors or more) have a model mode within the frequency window at MAC >= 0.9 (mean "
      "best MAC {:.3f}); with {} reversed, {} of {} have (mean {:.3f}), so {} likely wrong "
      "(mounted the other way round): give {}{} in the sensors file (a campaign's [[channel]] "
      "sign), or, if the sign{} right, fit the shapes as given with --trust-signs (a campaign's "
      "update.linear trust_signs = true)",
      one ? "" : "s", which, one ? "s" : "", c.matched, c.counted, c.mean_mac, which,
      c.matched_reversed, c.counted, c.mean_mac_reversed, one ? "its sign is" : "their signs are",
      fmt::join(signs, " and "), same_as_the_others(sensors, measured, c.channels),
      one ? " is" : "s are");
}

// update_linear() with the sensors' signs as given (after the start's shape checks); the
// one-at-a-time sweeps only where `with_sweeps`. The warnings on pairs followed below the MAC
// threshold go to `weak_pairs` (when given), not into s.warnings: update_linear() decides. The
// fit starts from `from` where given (the sets not held; within their bounds), else from the
// start; a flat set is held at the start either way. `end` receives the result's point where
// the fit reaches one (not where the pairs cannot be decided).
Eigen::VectorXd fit_as_given(const model::Model& model, const std::vector<std::string>& names,
                             const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                             const LinearUpdateOptions& options, bool with_sweeps,
                             LinearUpdateSummary& s, std::vector<PairWarning>* weak_pairs = nullptr,
                             const Eigen::VectorXd* from = nullptr,
                             std::optional<TrackedPoint>* end = nullptr) {
  const StiffnessSets sets(model, names);
  const LinearProblem p = make_problem(sets, model, names, sensors, measured, options);
  const int minimised = options.rule == LinearRule::kSmallest
                            ? set_index(names, options.smallest_set, "the smallest rule")
                            : -1;
  s = LinearUpdateSummary{};
  s.rule = options.rule == LinearRule::kSmallest
               ? fmt::format("smallest {} with every error within {:.3g} %", options.smallest_set,
                             100 * options.tolerance)
               : "least squares";

  // Held sets: where the user says (or at their start).
  const int n = p.size();
  std::vector<char> held(static_cast<size_t>(n), 0);
  Eigen::VectorXd begin = p.start.cwiseMax(p.lower).cwiseMin(p.upper);
  for (const ParameterHold& h : options.holds) {
    const int k = set_index(names, h.name, "hold");
    held[static_cast<size_t>(k)] = 1;
    if (h.value > 0) begin(k) = h.value;
  }
  if (minimised >= 0 && held[static_cast<size_t>(minimised)])
    throw InputError(fmt::format("the smallest rule: '{}' is held", options.smallest_set));

  // The start: pairs by the rules.
  Eigen::VectorXd first = begin;
  for (int k = 0; k < n && from; ++k)
    if (!held[static_cast<size_t>(k)]) first(k) = std::clamp((*from)(k), p.lower(k), p.upper(k));
  TrackedPoint point = p.fresh(first.array().log(), s.start);
  s.initial_cost = s.start.cost();
  s.final = s.start;
  s.final_cost = s.initial_cost;
  s.final_mac = s.start.mac;
  if (std::string why = shape_problem(s.start, sensors, measured, options); !why.empty()) {
    s.status = LinearUpdateStatus::kShapesRefused;
    s.shape_problem = std::move(why);
    return begin;
  }
  if (s.start.pairing.pairs.empty()) {
    s.status = LinearUpdateStatus::kTooFewPairs;
    return begin;
  }

  // Least squares with pairs followed by shape (settle(), below), from the start's pairs; when
  // the sensors cannot tell two candidates apart at the start, from each candidate pairing,
  // and the data decide between the results as they do at a result.
  const double sf2 = options.frequency_std * options.frequency_std;
  std::vector<Settled> outcomes;
  const std::vector<TrackedPoint> starts = candidate_pairings(point, s.start, s.start.ties.size());
  if (starts.size() > kMaxPairings) {
    s.status = LinearUpdateStatus::kAmbiguous;
    s.ambiguity = fmt::format(
        "at the start, {}; that leaves {} pairings to fit, more than {}: add sensors that see "
        "the modes apart",
        s.start.ambiguity, starts.size(), kMaxPairings);
    return begin;
  }
  // Two results with different pairs that each fit within the noise (2 cost / sigma_f^2 < 9)
  // cannot be told apart whatever the other starts give (no cost is below 0): those are not
  // fitted (a frequency-only table of the example beam has 16 pairings, 8 s each).
  const auto within_noise = [&](const Settled& o) { return 2 * o.cost / sf2 < 9; };
  for (const TrackedPoint& c : starts) {
    outcomes.push_back(settle(p, c, held));
    const Settled& last = outcomes.back();
    if (within_noise(last) &&
        std::any_of(outcomes.begin(), outcomes.end() - 1, [&](const Settled& o) {
          return within_noise(o) && o.point.columns != last.point.columns;
        }))
      break;
  }
  size_t win = 0;
  for (size_t k = 1; k < outcomes.size(); ++k)
    if (outcomes[k].cost < outcomes[win].cost) win = k;
  std::vector<std::string> start_costs;
  bool decided = true;
  std::vector<const TrackedPoint*> rivals;
  for (size_t k = 0; k < outcomes.size(); ++k) {
    start_costs.push_back(fmt::format("{:.4g}", outcomes[k].cost));
    // By mode number, as before: by shape (same_partners), the one-sensor beam's fits with rz
    // at 2129 and at 100 pair test mode 6 with other modes, and the update, which the beam
    // test pins as right (K_T moves by less than its sigma between them), would be refused.
    if (k != win && outcomes[k].point.columns != outcomes[win].point.columns &&
        2 * (outcomes[k].cost - outcomes[win].cost) / sf2 < 9) {
      decided = false;
      rivals.push_back(&outcomes[k].point);
    }
  }
  Settled& o = outcomes[win];
  s.status = o.status;
  s.iterations = o.record.iterations;
  s.history.insert(s.history.end(), o.record.history.begin(), o.record.history.end());
  s.theta_history.insert(s.theta_history.end(), o.record.theta_history.begin(),
                         o.record.theta_history.end());
  s.warnings = o.record.warnings;
  if (weak_pairs) *weak_pairs = o.weak_pairs;
  s.rounds = o.rounds;
  point = o.point;
  bool unconfirmed_refusal = false;
  if (o.ambiguity.empty()) {
    std::string warning;
    o.ambiguity = unconfirmed_sets(p, model.mass, starts[win], point, measured, options, held,
                                   names, &warning);
    unconfirmed_refusal = !o.ambiguity.empty();
    if (!warning.empty()) s.warnings.push_back(warning);
  }
  if (!decided && o.ambiguity.empty())
    o.ambiguity = fmt::format(
        "at the start, {}; fitting {} of the {} candidate pairings leaves costs {} that the "
        "data cannot tell apart",
        s.start.ambiguity, outcomes.size(), starts.size(), fmt::join(start_costs, ", "));
  // Flat sets are not identified by the frequencies: held (at their start) and the rest fitted
  // again. Where the pairs could not be decided between fits (not where they rest on sets only
  // unconfirmed pairs see), flat sets at the best of them are held first all the same: a set
  // the frequencies do not identify may drift between its bounds to either side of a veering,
  // and the pairs differ with the side, not with the data (the example beam's spring.rz at 0.1
  // and at 1e5, its sixth bending mode on either branch, "cannot be decided" in 3 of 12 seeds of
  // 0.1 % noise, where rz held at 100 pairs it beyond doubt).
  const std::string undecided = unconfirmed_refusal ? std::string() : o.ambiguity;
  report_sensitivity(p, p.evaluate(point), s);
  for (int k = 0; k < n; ++k) s.parameters[k].held_by_user = held[static_cast<size_t>(k)];
  const auto holds_flat = [&](int k) {
    return s.parameters[k].flat && !held[static_cast<size_t>(k)] && k != minimised;
  };
  // Only a set flat at every result that fits as well is held for it: a set flat at the best
  // result because of its pairs alone (chain B's kb, where the one measured mode sits on chain
  // A's mode, and ka where it sits on B's) leaves the pairs undecided whatever it is held at.
  for (const TrackedPoint& r : o.rivals) rivals.push_back(&r);
  std::vector<LinearEvaluation> at_rivals;
  if (!undecided.empty())
    for (const TrackedPoint* r : rivals) at_rivals.push_back(p.evaluate(*r));
  bool any_flat = false;
  for (int k = 0; k < n; ++k)
    any_flat = any_flat ||
               (holds_flat(k) &&
                std::all_of(at_rivals.begin(), at_rivals.end(), [&](const LinearEvaluation& e) {
                  return e.jacobian.rows() > 0 &&
                         e.jacobian.col(k).cwiseAbs().maxCoeff() < options.flat_sensitivity;
                }));
  if (!o.ambiguity.empty() && (undecided.empty() || !any_flat)) {
    s.status = LinearUpdateStatus::kAmbiguous;
    s.ambiguity = o.ambiguity;
    s.final = p.evaluate(point);
    s.final_cost = s.final.cost();
    s.final_mac = s.final.mac;
    return point.x.array().exp();
  }
  LinearEvaluation fresh_end = std::move(o.fresh_end);
  bool refit = false;
  Eigen::VectorXd x_held = point.x;
  std::vector<std::string> held_flat;
  for (int k = 0; k < n; ++k) {
    if (!holds_flat(k)) continue;
    held[static_cast<size_t>(k)] = 1;
    const double at = std::exp(point.x(k));
    x_held(k) = begin.array().log()(k);
    refit = true;
    held_flat.push_back(names[k]);
    s.parameters[k].drifted_to = at;
    s.parameters[k].drifted_sensitivity = s.parameters[k].sensitivity;
    s.warnings.push_back(fmt::format(
        "{} is flat (sensitivity {:.3g} < {:.3g}): the frequencies do not identify it; held "
        "at {:.6g} (it had drifted to {:.6g}); hold it elsewhere with --hold {}=VALUE",
        names[k], s.parameters[k].sensitivity, options.flat_sensitivity, std::exp(x_held(k)), at,
        names[k]));
  }
  if (!undecided.empty())
    s.warnings.push_back(fmt::format(
        "with the flat {} {} fitted too the pairs could not be decided ({}); flat at the best "
        "of those fits, {} held at {} start and the pairs made afresh there",
        held_flat.size() == 1 ? "set" : "sets", fmt::join(held_flat, ", "), undecided,
        held_flat.size() == 1 ? "it is" : "they are", held_flat.size() == 1 ? "its" : "their"));
  if (refit) {
    // A hold moves a set along no path the data chose, so the pairs followed there prove
    // nothing: following shapes back through a veering keeps to its branch (the lower stays the
    // lower), and the example beam's rz, driven to 1e5 and held back at 100, paired its sixth
    // bending mode with the twisting mode there (MAC 0.09, 4.3 % off, the bending mode at MAC
    // 1.00 beside it). The pairs are made afresh at the held point, as at the start (the
    // followed ones where the sensors cannot decide), and settled as a fit's result is.
    LinearEvaluation here;
    TrackedPoint again = p.fresh(x_held, here);
    std::optional<TrackedPoint> followed;
    if (!here.ambiguity.empty()) followed = p.move(point, x_held, 8);
    Settled h = settle(p, followed ? std::move(*followed) : std::move(again), held);
    s.status = h.status;
    s.iterations += h.record.iterations;
    s.rounds += h.rounds;
    s.history.insert(s.history.end(), h.record.history.begin(), h.record.history.end());
    s.theta_history.insert(s.theta_history.end(), h.record.theta_history.begin(),
                           h.record.theta_history.end());
    s.warnings.insert(s.warnings.end(), h.record.warnings.begin(), h.record.warnings.end());
    if (weak_pairs) *weak_pairs = h.weak_pairs;
    point = std::move(h.point);
    fresh_end = std::move(h.fresh_end);
    if (!h.ambiguity.empty()) {
      s.status = LinearUpdateStatus::kAmbiguous;
      s.ambiguity = fmt::format("with the flat sets held: {}", h.ambiguity);
      s.final = p.evaluate(point);
      s.final_cost = s.final.cost();
      s.final_mac = s.final.mac;
      return point.x.array().exp();
    }
  }
  const LinearEvaluation least_squares = p.evaluate(point);

  if (options.rule == LinearRule::kSmallest) {
    smallest_rule(p, minimised, held, point, s);
  } else if (options.tolerance > 0) {
    smallest_flat(p, point, s);
  }
  const Eigen::VectorXd theta = point.x.array().exp();
  LinearEvaluation at = p.evaluate(point);
  at.hidden = fresh_end.hidden;
  {
    // Sensitivities and uncertainty of the result itself.
    std::vector<char> flat(static_cast<size_t>(n));
    for (int k = 0; k < n; ++k) flat[static_cast<size_t>(k)] = s.parameters[k].flat;
    report_sensitivity(p, at, s);
    for (int k = 0; k < n; ++k) {
      s.parameters[k].flat = flat[static_cast<size_t>(k)];
      s.parameters[k].held = held[static_cast<size_t>(k)];
    }
  }
  report_uncertainty(p, theta, at, least_squares, held, s);
  // At the least-squares point only: a rule that moved on from it (tolerance, smallest) leaves a
  // cost the others' refit can lower whichever way a set moves.
  if (options.rule == LinearRule::kLeastSquares && !(options.tolerance > 0))
    report_one_sided(p, point, at, held, s);
  warn_bounds(p, theta, s);
  warn_aliased(p, at, s);
  if (with_sweeps) sweeps(p, point, s);
  if (end) *end = point;
  s.final_cost = at.cost();
  s.final_mac = at.mac;
  s.final = std::move(at);
  return theta;
}

bool fitted(const LinearUpdateSummary& s) {
  return s.status == LinearUpdateStatus::kConverged ||
         s.status == LinearUpdateStatus::kIterationLimit;
}

// A fit that leaves scatter beyond the noise (reduced_chi2_limit, the report's model-form
// threshold) may have stopped in a local minimum rather than found the model wanting. A lap
// joint (two 0.6 m strips lapped over 0.3 m, 6 rivets, one sensor at the far tip, the model's
// third mode not in the table, K_T started at 2e7 against 6e7) stopped at K_T 1.3-1.9e9
// (+/- 2000 %) with a reduced chi-square of 64-82 in 3 of 8 noise seeds, and the report called
// it a model-form error; from K_T ten times higher or lower each fits to 0.04-0.2 with K_T
// 6.0-6.5e7. So such a fit is fitted again from each set's start (not held by the user) times
// and divided by 10, one set at a time, the others at their start (within the bounds, which
// stay those of the start); each is a whole fit, its pairs judged by the rules as any fit's.
// The lowest cost wins where its reduced chi-square is lower too (over at least as many pairs,
// a degree of freedom left), each by more than a thousandth, else the earlier stays (minima
// equal to rounding are one). s.restarts says what was tried and which won. s keeps the
// start's evaluation and cost; its history is the winner's. `theta`, `end` and `weak_pairs`
// follow the winner.
void restart_if_misfit(const model::Model& model, const std::vector<std::string>& names,
                       const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                       const LinearUpdateOptions& options, LinearUpdateSummary& s,
                       Eigen::VectorXd& theta, std::optional<TrackedPoint>& end,
                       std::vector<PairWarning>* weak_pairs) {
  if (!fitted(s) || s.degrees_of_freedom < 1 ||
      !(s.reduced_chi2 > reduced_chi2_limit(s.degrees_of_freedom)))
    return;
  const StiffnessSets sets(model, names);
  const LinearProblem p = make_problem(sets, model, names, sensors, measured, options);
  const Eigen::VectorXd begin = p.start.cwiseMax(p.lower).cwiseMin(p.upper);
  std::vector<std::string> tried, skipped;
  std::string won;
  const double given_chi2 = s.chi2;
  const int given_dof = s.degrees_of_freedom;
  // The sensitivity of set k at an evaluation (-1: nothing paired to judge it by).
  const auto sensitivity = [](const LinearEvaluation& e, int k) {
    return e.jacobian.rows() > 0 ? e.jacobian.col(k).cwiseAbs().maxCoeff() : -1.0;
  };
  bool within_noise = false, cut_short = false;
  for (int k = 0; k < p.size() && !cut_short; ++k) {
    if (std::any_of(options.holds.begin(), options.holds.end(),
                    [&](const ParameterHold& h) { return h.name == names[k]; }))
      continue;
    for (const double factor : {10.0, 0.1}) {
      if (within_noise) {
        cut_short = true;
        break;
      }
      Eigen::VectorXd from = begin;
      from(k) = std::clamp(p.start(k) * factor, p.lower(k), p.upper(k));
      if (!(std::abs(std::log(from(k) / begin(k))) > 1e-3)) continue;  // a bound at the start
      const std::string which =
          fmt::format("{} {} ({:.4g})", names[k], factor > 1 ? "x10" : "/10", from(k));
      // A set flat at the start and at the restart's start (sensitivity below flat_sensitivity
      // at both: moving it there changes no frequency by more than a few tenths of a per cent)
      // leaves the other sets the landscape they had, and the flat rule holds it back at its
      // start in the end. The example beam's kz, rxy and rz (sensitivity 1e-13 to 5e-5) were 6 of
      // its 8 restarts, about 3 s of CPU each: over 3 seeds of 0.3 % noise (0.1 % stated) 16 of
      // those 18 fits came back to the given fit and 2 to one that did not win.
      const double here = sensitivity(s.start, k);
      if (here >= 0 && here < options.flat_sensitivity) {
        LinearEvaluation e;
        p.fresh(from.array().log(), e);
        const double there = sensitivity(e, k);
        if (there >= 0 && there < options.flat_sensitivity) {
          skipped.push_back(fmt::format("{} (sensitivity {:.2g} there, {:.2g} at the start)", which,
                                        there, here));
          continue;
        }
      }
      LinearUpdateSummary r;
      std::vector<PairWarning> w;
      std::optional<TrackedPoint> e;
      Eigen::VectorXd t =
          fit_as_given(model, names, sensors, measured, options, false, r, &w, &from, &e);
      ++s.starts;
      if (!fitted(r)) {
        tried.push_back(fmt::format("{} ended {}", which,
                                    r.status == LinearUpdateStatus::kAmbiguous
                                        ? "with pairs it could not decide"
                                        : "without a result"));
        continue;
      }
      tried.push_back(
          fmt::format("{} left {}{}", which,
                      r.degrees_of_freedom >= 1
                          ? fmt::format("{:.3g} over {}", r.reduced_chi2, r.degrees_of_freedom)
                          : "no degree of freedom",
                      r.final.pairing.pairs.size() < s.final.pairing.pairs.size()
                          ? fmt::format(" pairing {} of {} modes", r.final.pairing.pairs.size(),
                                        measured.frequency_hz.size())
                          : ""));
      // Lower in all and per degree of freedom: a set the flat rule held at one result and
      // fitted at another lowers the chi-square by being freed alone (the chain and rotor's kt,
      // held flat at 4.4e3: 220 over 2; fitted from 4.4e4 to 5140: 195 over 1), and holding one
      // lowers it per degree of freedom (the two chains, noise five times the stated: 172 over
      // 3, and with kb flat 176 over 4).
      if (r.degrees_of_freedom < 1 || r.final.pairing.pairs.size() < s.final.pairing.pairs.size() ||
          !(r.chi2 < s.chi2 * (1 - 1e-3)) || !(r.reduced_chi2 < s.reduced_chi2 * (1 - 1e-3)))
        continue;
      won = which;
      r.start = std::move(s.start);
      r.initial_cost = s.initial_cost;
      r.starts = s.starts;
      s = std::move(r);
      theta = std::move(t);
      end = std::move(e);
      if (weak_pairs) *weak_pairs = std::move(w);
      // Within the noise the misfit was the search's: no later start is needed to say so (the
      // lap joint's K_T x10, the first tried, fitted each of its stuck seeds so, and the 3 more
      // restarts after it cost 3 whole fits each).
      within_noise = s.reduced_chi2 <= reduced_chi2_limit(s.degrees_of_freedom);
    }
  }
  if (tried.empty() && skipped.empty()) return;
  const bool misfit =
      s.degrees_of_freedom >= 1 && s.reduced_chi2 > reduced_chi2_limit(s.degrees_of_freedom);
  const std::string not_fitted =
      skipped.empty()
          ? std::string()
          : fmt::format(
                "; not fitted from {}: flat there and at the start (sensitivity below {:.3g}), so "
                "the frequencies hardly see the move and the other sets would start as they did",
                fmt::join(skipped, ", "), options.flat_sensitivity);
  const std::string outcome =
      tried.empty() ? "so the result is the start's"
      : won.empty() ? fmt::format("none fitted better, so the result is the start's{}",
                                  misfit ? " and the misfit no search from there removes" : "")
                    : fmt::format("the fit from {} won (its result is the one reported){}", won,
                                  misfit      ? ", and still leaves scatter beyond the noise"
                                  : cut_short ? "; within the noise, so no other start was tried"
                                              : "");
  s.restarts = fmt::format(
      "restarts: from the start the fit left a reduced chi-square of {:.3g} over {} degrees of "
      "freedom, beyond the noise (above {:.3g}), so it was fitted again from {} other start{} "
      "(each set's start times and divided by 10, one at a time){}{}{}; {}",
      given_chi2 / given_dof, given_dof, reduced_chi2_limit(given_dof), tried.size(),
      tried.size() == 1 ? "" : "s", tried.empty() ? "" : ": ", fmt::join(tried, ", "), not_fitted,
      outcome);
  // Only now is a misfit beyond the noise the model's: the warning says from how many starts.
  for (std::string& x : s.warnings) {
    const std::string tag = "(model-form error)";
    if (const size_t at = x.find(tag); at != std::string::npos)
      x.replace(at, tag.size(), fmt::format("(model-form error, from {} starts)", s.starts));
  }
}

// Why a fit's misfit is one or two channels read reversed, or "". The start's check
// (shape_problem) cannot tell when every measured mode matches some model mode either way:
// on the example beam with s2 and s4 reversed and modes 1, 4 and 5 alone, all three matched as
// given, the fit paired mode 5 with a model mode 38 % away and gave K_T 5.1e6 against 1.2e7,
// "converged", with reduced chi-square 7.6e4. So where a fit leaves scatter beyond the noise
// (reduced_chi2_limit) and the reversal that matches the shapes best at the start matches as
// many modes with a higher mean MAC (SignCheck::best_looks_better), that reversal is fitted
// too; when it pairs as many modes and its reduced chi-square is within the noise, or a
// hundredth of the given signs' (a model-form error both share), the signs are refused.
std::string misfit_of_signs(const model::Model& model, const std::vector<std::string>& names,
                            const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                            const LinearUpdateOptions& options, const LinearUpdateSummary& s) {
  // The scatter per degree of freedom and where noise keeps it; with none left (as many pairs
  // as fitted sets) the whole chi-square, which a fit that reached every frequency leaves near
  // 0, against 3 sigma at each pair (a bound stopped it, or pairs no stiffness can meet).
  const double sf2 = options.frequency_std * options.frequency_std;
  const auto misfit = [&](const LinearUpdateSummary& x) {
    if (x.degrees_of_freedom >= 1)
      return std::pair{x.reduced_chi2, reduced_chi2_limit(x.degrees_of_freedom)};
    return std::pair{x.final.weighted_squared_norm() / sf2,
                     9.0 * static_cast<double>(x.final.pairing.pairs.size())};
  };
  const auto [given, given_limit] = misfit(s);
  if (options.trust_signs || !fitted(s) || !(given > given_limit)) return "";
  const SignCheck c =
      check_channel_signs(measured.shapes, measured.frequency_hz, s.start.model_at_sensors,
                          s.start.all_model_frequency_hz, s.start.hidden, options.frequency_window);
  if (!c.best_looks_better()) return "";
  std::vector<Sensor> reversed = sensors;
  std::vector<std::string> which, signs;
  for (const int k : c.best) {
    Sensor& r = reversed[static_cast<size_t>(k)];
    r.sign = -r.sign;
    which.push_back(r.channel);
    signs.push_back(fmt::format("{} sign {:+g}", r.channel, r.sign));
  }
  LinearUpdateOptions o = options;
  o.trust_signs = true;
  o.progress = nullptr;
  LinearUpdateSummary r;
  fit_as_given(model, names, reversed, measured, o, false, r);
  if (!fitted(r) || (s.degrees_of_freedom >= 1 && r.degrees_of_freedom < 1) ||
      r.final.pairing.pairs.size() < s.final.pairing.pairs.size())
    return "";
  const auto [again, again_limit] = misfit(r);
  if (!(again <= std::max(again_limit, given / 100))) return "";
  const std::string scatter =
      s.degrees_of_freedom >= 1
          ? fmt::format("a reduced chi-square of {:.3g} over {} degrees of freedom", given,
                        s.degrees_of_freedom)
          : fmt::format("a chi-square of {:.3g} with no degree of freedom left", given);
  const bool one = which.size() == 1;
  return fmt::format(
      "channel{} {} likely read{} the model reversed: as given, the fit leaves {} (largest "
      "frequency error {:.3g} %), beyond the noise the frequencies state; with {} reversed it "
      "leaves {:.3g} (largest error {:.3g} %), pairing {} of {} measured modes, so the fit tells "
      "what the shapes alone did not: give {}{} in the sensors file (a campaign's [[channel]] "
      "sign), or, if the sign{} right, fit the shapes as given with --trust-signs (a campaign's "
      "update.linear trust_signs = true)",
      one ? "" : "s", fmt::join(which, " and "), one ? "s" : "", scatter, 100 * s.final.max_error(),
      fmt::join(which, " and "), again, 100 * r.final.max_error(), r.final.pairing.pairs.size(),
      measured.frequency_hz.size(), fmt::join(signs, " and "),
      same_as_the_others(sensors, measured, c.best), one ? " is" : "s are");
}

// `measured` without mode (column) `drop`.
MeasuredModes without_mode(const MeasuredModes& measured, Eigen::Index drop) {
  std::vector<Eigen::Index> keep;
  for (Eigen::Index i = 0; i < measured.frequency_hz.size(); ++i)
    if (i != drop) keep.push_back(i);
  return measured.columns(keep);
}

// Why a fit's misfit is one measured mode that the model does not match, or "". A trial's lap
// joint (three sensors on one strip, five bending modes with 0.1 % noise and a sixth row at
// 450 Hz with a shape of noise, a mode the model does not have) paired that row with a torsion
// mode at 355 Hz (MAC 0.82 at three sensors, -21 %), and the fit drove K_T to 1e10 and spring.rxy
// to 6.8e5 to meet it: "converged", reduced chi-square 9.7e3, K_T then "held (flat)" at its start
// (truth 4e7), in 3 of 6 seeds. So where a fit leaves scatter beyond the noise, and by far
// (reduced chi-square at least 100), each paired mode (the 8 of largest error at most) is left out
// in turn and the rest fitted again; those whose leaving out pairs every other mode and leaves
// scatter within the noise (and a hundredth of the given, or less) are named and the update
// refused: a mode the model does not have, a wrong frequency, or a model that lacks what moves it.
// One is named alone only where its refit's chi-square is below every other's by 9 or more (3
// sigma): with the two-chain structure's first mode 15 % high, leaving out its fifth mode also
// fits within the noise (a chi-square of 7.3 over 2 degrees of freedom, ka moved from 5e5 to
// 2.4e6 past a crossing) and the largest error at the result was the fifth's, not the first's.
std::string misfit_of_one_mode(const model::Model& model, const std::vector<std::string>& names,
                               const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                               const LinearUpdateOptions& options, const LinearUpdateSummary& s) {
  const double given = s.reduced_chi2;
  if (!fitted(s) || s.degrees_of_freedom < 2 ||
      !(given > std::max(100.0, reduced_chi2_limit(s.degrees_of_freedom))))
    return "";
  const LinearEvaluation& e = s.final;
  // The largest errors in sigmas of their own modes first.
  const auto weighted = [&](int i) {
    return e.residuals(i) * (e.weights.size() == e.residuals.size() ? e.weights(i) : 1.0);
  };
  std::vector<int> order;
  for (const ModePair& q : e.pairing.pairs) order.push_back(q.measured);
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return std::abs(weighted(a)) > std::abs(weighted(b)); });
  if (order.size() > 8) order.resize(8);
  struct Without {
    int mode = -1;
    double chi2 = 0;  // the refit's chi-square (not reduced)
    std::string text;
  };
  std::vector<Without> fits;
  LinearUpdateOptions o = options;
  o.progress = nullptr;
  // Each refit from the start first; where none fits within the noise, those of the 3 largest
  // errors again from the restarts (restart_if_misfit; 2 per set each, so at most 6 per set in
  // all, on a result that was wrong anyway): the lap joint above with a row at 300 Hz the model
  // does not have, left out, stopped where the whole table had (K_T 1.5e9) in 4 of 6 seeds, and
  // the update ended "converged" with K_T held (flat) at 2e7 against 6e7.
  struct Refit {
    int mode;
    LinearUpdateSummary r;
    Eigen::VectorXd theta;
  };
  std::vector<Refit> refits;
  for (const int i : order) {
    Refit f{i, {}, {}};
    f.theta = fit_as_given(model, names, sensors, without_mode(measured, i), o, false, f.r);
    refits.push_back(std::move(f));
  }
  const auto judge = [&](const Refit& f) {
    const int i = f.mode;
    const LinearUpdateSummary& r = f.r;
    const Eigen::VectorXd& theta = f.theta;
    if (!fitted(r) || r.degrees_of_freedom < 1 ||
        r.final.pairing.pairs.size() + 1 < e.pairing.pairs.size())
      return;
    const double again = r.reduced_chi2;
    if (!(again <= reduced_chi2_limit(r.degrees_of_freedom)) ||
        !(given >= 100 * std::max(again, 1.0)))
      return;
    std::vector<std::string> values;
    for (size_t k = 0; k < names.size() && k < r.parameters.size(); ++k)
      values.push_back(fmt::format("{} {:.4g}{}", names[k], theta(static_cast<Eigen::Index>(k)),
                                   r.parameters[k].held ? " (held)" : ""));
    fits.push_back(
        {i, again * r.degrees_of_freedom,
         fmt::format("{:.3g} over {} (largest error {:.3g} %; {}{})", again, r.degrees_of_freedom,
                     100 * r.final.max_error(), fmt::join(values, ", "),
                     r.starts > 1 ? fmt::format("; the best of {} starts", r.starts) : "")});
  };
  for (const Refit& f : refits) judge(f);
  if (fits.empty()) {
    for (size_t q = 0; q < refits.size() && q < 3; ++q) {
      Refit& f = refits[q];
      const MeasuredModes without = without_mode(measured, f.mode);
      std::optional<TrackedPoint> end;
      restart_if_misfit(model, names, sensors, without, o, f.r, f.theta, end, nullptr);
      judge(f);
    }
  }
  if (fits.empty()) return "";
  std::sort(fits.begin(), fits.end(),
            [](const Without& a, const Without& b) { return a.chi2 < b.chi2; });
  // A mode without a shape the MAC can read rests on the nearest model frequency at the start,
  // which a start far from the truth gets wrong: a trial's lap joint at one sensor (model mode 3
  // not in the table, K_T started at a third of the truth) paired its 376 Hz mode with model mode
  // 7 (385 Hz at the start) where the truth's mode 6 (359 Hz at the start) is it, in 3 of 8
  // seeds, and blaming the mode alone would have had the user drop a mode the model has.
  const auto by_frequency = [&](int i) {
    return static_cast<size_t>(i) < e.mac_reads_shape.size() &&
           !e.mac_reads_shape[static_cast<size_t>(i)];
  };
  const auto partner = [&](int i) {
    if (!by_frequency(i)) return fmt::format("paired with {}", pair_text(e, i));
    const int j = e.pairing.model_for(i);
    int next = -1;
    for (int k = 0; k < static_cast<int>(e.all_model_frequency_hz.size()); ++k) {
      if (k == j) continue;
      const double d = std::abs(std::log(e.all_model_frequency_hz(k) / measured.frequency_hz(i)));
      if (next < 0 ||
          d < std::abs(std::log(e.all_model_frequency_hz(next) / measured.frequency_hz(i))))
        next = k;
    }
    return fmt::format(
        "paired by frequency alone (no shape at two sensors) with model mode {} ({:.5g} Hz; the "
        "next nearest is model mode {}, {:.5g} Hz)",
        j + 1, e.all_model_frequency_hz(j), next + 1,
        next >= 0 ? e.all_model_frequency_hz(next) : 0.0);
  };
  const std::string noise = stated_noise(options.frequency_std, s.mode_frequency_std,
                                         [&](Eigen::Index i) { return measured.id(i); });
  if (fits.size() == 1 || fits[1].chi2 - fits[0].chi2 >= 9) {
    const int i = fits[0].mode;
    const std::string head = fmt::format(
        "test mode {} ({:.5g} Hz), {}, {:+.3g} % off, leaves a reduced chi-square of {:.3g} over "
        "{} degrees of freedom (largest frequency error {:.3g} %), far beyond the stated noise "
        "({}); without it the other {} pair and fit to {}, within that noise",
        measured.id(i), measured.frequency_hz(i), partner(i), 100 * e.residuals(i), given,
        s.degrees_of_freedom, 100 * e.max_error(), noise, e.pairing.pairs.size() - 1, fits[0].text);
    if (by_frequency(i)) {
      return fmt::format(
          "{}. Without a shape its pair rests on the nearest model frequency at the start, which "
          "a start far from the truth gets wrong, or it may be a mode the model does not have or "
          "a wrong frequency: give its shape at two sensors or more, or start the sets nearer "
          "(the model file's values; the fit without it is above), or leave it out of the table "
          "(its row; in a campaign, list the other [[mode]] names in [update.linear] modes) to "
          "update on the others",
          head);
    }
    return fmt::format(
        "{}. It is likely one the model does not match: a mode the model does not have (an "
        "in-plane, torsion or fixture mode, or a spurious peak), a wrong frequency, or the model "
        "may lack what moves it: check it, and leave it out of the table (its row; in a "
        "campaign, list the other [[mode]] names in [update.linear] modes) to update on the "
        "others",
        head);
  }
  std::vector<std::string> ids, each;
  for (const Without& w : fits) {
    ids.push_back(measured.id(w.mode));
    each.push_back(
        fmt::format("without test mode {} ({:.5g} Hz, {}, {:+.3g} % off) the others "
                    "fit to {}",
                    measured.id(w.mode), measured.frequency_hz(w.mode), partner(w.mode),
                    100 * e.residuals(w.mode), w.text));
  }
  return fmt::format(
      "one of test modes {} is likely one the model does not match or paired wrongly, and the "
      "data cannot tell which: the fit leaves a reduced chi-square of {:.3g} over {} degrees of "
      "freedom (largest frequency error {:.3g} %), far beyond the stated noise ({}); {}, "
      "each within that noise. Check those modes (a mode the model does not have, a wrong "
      "frequency, a pair by frequency alone from a start far from the truth, or a model that "
      "lacks what moves it), and leave the one that is wrong out of the table (its row; in a "
      "campaign, list the other [[mode]] names in [update.linear] modes)",
      fmt::join(ids, ids.size() == 2 ? " and " : ", "), given, s.degrees_of_freedom,
      100 * e.max_error(), noise, fmt::join(each, "; "));
}

// The pairs at the result whose MAC with their partner is below the threshold (a shape at two
// sensors or more): they rest on the start's MACs and on following each mode's shape, not on the
// shapes themselves. With two sensors the start's MACs are weak evidence: a sign wrong at one of
// them turns one shape into the other (the sign checks need three), and the trial's twin
// cantilevers with channel a reversed paired their first two modes crosswise at MAC 0.96-0.97,
// the fit then pulled the coupling spring from 200 to 6.8 until the modes' shapes no longer
// told them apart (MAC 0.48 and 0.49 at the result, errors +9.98 % and -16.5 %), and the
// headline said "converged". Returns the line for the report naming them, why, and what to do
// ("" when every pair is confirmed), their rows in s.unconfirmed_modes.
std::string unconfirmed_pairs(const MeasuredModes& measured, const LinearUpdateOptions& options,
                              LinearUpdateSummary& s) {
  const LinearEvaluation& e = s.final;
  std::vector<char> hidden(static_cast<size_t>(e.all_model_frequency_hz.size()), 0);
  for (const int j : e.hidden) hidden[static_cast<size_t>(j)] = 1;
  std::vector<std::string> ids, lines;
  bool two_sensors = false;
  for (const ModePair& q : e.pairing.pairs) {
    const std::optional<double> mac = e.pair_mac(q.measured);
    if (!mac || *mac >= options.mac_threshold) continue;
    const Eigen::Index i = q.measured;
    const double fe = e.measured_frequency_hz(i);
    int other = -1;
    for (Eigen::Index j = 0; j < e.mac.cols(); ++j) {
      const double f = e.all_model_frequency_hz(j);
      if (j == q.model || hidden[static_cast<size_t>(j)] || !(f > 0) ||
          (options.frequency_window > 0 && std::abs(f / fe - 1) > options.frequency_window))
        continue;
      if (other < 0 || e.mac(i, j) > e.mac(i, other)) other = static_cast<int>(j);
    }
    two_sensors = two_sensors || (measured.shapes.col(i).array().abs() > 0.0).count() == 2;
    ids.push_back(e.measured_id(i));
    lines.push_back(fmt::format(
        "test mode {} ({:.5g} Hz) has MAC {:.3f} with its partner, model mode {} ({:.5g} Hz){}",
        e.measured_id(i), fe, *mac, q.model + 1, e.model_frequency_hz(i),
        other < 0 ? ""
                  : fmt::format(", and {:.3f} with model mode {} ({:.5g} Hz)", e.mac(i, other),
                                other + 1, e.all_model_frequency_hz(other))));
    s.unconfirmed_modes.push_back(static_cast<int>(i));
  }
  const double sf2 = options.frequency_std * options.frequency_std;
  const bool misfit =
      s.degrees_of_freedom > 0
          ? s.reduced_chi2 > reduced_chi2_limit(s.degrees_of_freedom)
          : e.weighted_squared_norm() / sf2 > 9.0 * static_cast<double>(e.pairing.pairs.size());
  // Pairs crosswise to the frequency order (the lower test mode with the higher model mode), each
  // shape at two sensors, where the fit leaves a misfit: their MACs confirm nothing, as one sign
  // wrong turns one shape into the other. The twin cantilevers' first two modes alone, channel a
  // reversed, paired crosswise at MAC 0.973 and 0.973 at the result, errors +14.1 % and -15.9 %
  // at a reduced chi-square of 4.5e4, and were called converged.
  const auto at_two = [&](Eigen::Index i) {
    return (measured.shapes.col(i).array().abs() > 0.0).count() == 2;
  };
  const auto listed = [&](int i) {
    return std::find(s.unconfirmed_modes.begin(), s.unconfirmed_modes.end(), i) !=
           s.unconfirmed_modes.end();
  };
  for (const ModePair& p : e.pairing.pairs) {
    for (const ModePair& q : e.pairing.pairs) {
      const double fp = e.measured_frequency_hz(p.measured),
                   fq = e.measured_frequency_hz(q.measured);
      if (!misfit || !(fp < fq) ||
          !(e.all_model_frequency_hz(p.model) > e.all_model_frequency_hz(q.model)) ||
          !at_two(p.measured) || !at_two(q.measured) || listed(p.measured) || listed(q.measured))
        continue;
      two_sensors = true;
      ids.push_back(e.measured_id(p.measured));
      ids.push_back(e.measured_id(q.measured));
      lines.push_back(fmt::format(
          "test modes {} ({:.5g} Hz) and {} ({:.5g} Hz) pair crosswise to the frequency order, "
          "with model modes {} ({:.5g} Hz) and {} ({:.5g} Hz), at MAC {:.3f} and {:.3f}",
          e.measured_id(p.measured), fp, e.measured_id(q.measured), fq, p.model + 1,
          e.all_model_frequency_hz(p.model), q.model + 1, e.all_model_frequency_hz(q.model),
          e.pair_mac(p.measured).value_or(p.mac), e.pair_mac(q.measured).value_or(q.mac)));
      s.unconfirmed_modes.push_back(p.measured);
      s.unconfirmed_modes.push_back(q.measured);
    }
  }
  if (lines.empty()) return "";
  const bool one = ids.size() == 1;
  return fmt::format(
      "the shapes do not confirm the pair{} of test mode{} {}: at the result {} (the MAC "
      "threshold is {:g}); {} on the start's MACs and on following each mode's shape{}{}: add "
      "sensors that see these modes apart, or check the signs of their shapes (a campaign's "
      "[[channel]] sign); to pair a mode by frequency alone, give its shape at one sensor only "
      "(the other cells of its modes-table row empty); in a campaign (jointlab run), whose shapes "
      "come from every [[channel]], leave test mode{} {} out of the linear update (list the other "
      "[[mode]] names in [update.linear] modes)",
      one ? "" : "s", one ? "" : "s", fmt::join(ids, one ? "" : " and "), fmt::join(lines, "; "),
      options.mac_threshold, one ? "it rests" : "they rest",
      two_sensors ? ", and at two sensors a MAC tells shapes apart poorly: one sign wrong (a "
                    "channel mounted reversed, or a mode's phase) turns one shape into the "
                    "other, and the channel sign checks need three sensors"
                  : "",
      misfit
          ? fmt::format("; the fit leaves {} (largest frequency error {:.3g} %), which wrong pairs "
                        "would explain",
                        s.degrees_of_freedom > 0
                            ? fmt::format("a reduced chi-square of {:.3g}", s.reduced_chi2)
                            : fmt::format("a chi-square of {:.3g} with no degree of freedom left",
                                          e.weighted_squared_norm() / sf2),
                        100 * e.max_error())
          : "",
      one ? "" : "s", fmt::join(ids, one ? "" : " and "));
}

}  // namespace

Eigen::VectorXd update_linear(const model::Model& model, const std::vector<std::string>& names,
                              const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                              const LinearUpdateOptions& options, LinearUpdateSummary* summary) {
  if (const std::string e = options.error(); !e.empty()) throw InputError("update-linear: " + e);
  check_measured(sensors, measured);
  // Files of a mode that disagree widen that mode's frequency uncertainty (mode_sigma): its
  // residual weighs less, and only the sets it fixes widen.
  if (measured.frequency_std.size() > 0 &&
      (measured.frequency_std.size() != measured.frequency_hz.size() ||
       !(measured.frequency_std.array() >= 0).all() || !measured.frequency_std.allFinite()))
    throw InputError("measured modes: frequency_std must be finite and >= 0, one per mode");
  LinearUpdateSummary local;
  LinearUpdateSummary& s = summary ? *summary : local;
  std::vector<PairWarning> weak_pairs;
  std::optional<TrackedPoint> end;
  Eigen::VectorXd theta =
      fit_as_given(model, names, sensors, measured, options, false, s, &weak_pairs, nullptr, &end);
  restart_if_misfit(model, names, sensors, measured, options, s, theta, end, &weak_pairs);
  if (end) {
    // The one-at-a-time sweeps of the result kept (the winner's where a restart won).
    const StiffnessSets sets(model, names);
    sweeps(make_problem(sets, model, names, sensors, measured, options), *end, s);
  }
  if (std::string why = misfit_of_signs(model, names, sensors, measured, options, s);
      !why.empty()) {
    s.status = LinearUpdateStatus::kShapesRefused;
    s.shape_problem = std::move(why);
  } else if (std::string one = misfit_of_one_mode(model, names, sensors, measured, options, s);
             !one.empty()) {
    s.status = LinearUpdateStatus::kShapesRefused;
    s.shape_problem = std::move(one);
  }
  if (fitted(s)) {
    if (std::string why = unconfirmed_pairs(measured, options, s); !why.empty()) {
      s.fit_converged = s.status == LinearUpdateStatus::kConverged;
      s.status = LinearUpdateStatus::kPairsUnconfirmed;
      s.unconfirmed = std::move(why);
    }
  }
  // A weak pair is warned of once: not again where the unconfirmed line names its mode.
  std::vector<std::string> weak;
  for (PairWarning& w : weak_pairs) {
    if (std::find(s.unconfirmed_modes.begin(), s.unconfirmed_modes.end(), w.measured) ==
        s.unconfirmed_modes.end())
      weak.push_back(std::move(w.text));
  }
  s.warnings.insert(s.warnings.begin(), weak.begin(), weak.end());
  s.warnings.insert(s.warnings.begin(), measured.warnings.begin(), measured.warnings.end());
  return theta;
}

namespace {

// Where the degrees of freedom are too few to check the stated noise: how often noise three
// times the stated would scatter as little as the result's (a chi-square of dof * reduced / 9
// or less), when that is 5 % or more; else "". The chain and rotor with 0.3 % noise and the
// default 0.1 % stated, one degree of freedom left, gave a reduced chi-square of 0.99 and kg at
// +/- 0.344 %, 6.5 of those from the truth: three times the noise scatters so little 26 % of
// the time.
std::string few_degrees_note(const LinearUpdateSummary& s) {
  if (s.degrees_of_freedom <= 0 || !(s.reduced_chi2 >= 0)) return "";
  const boost::math::chi_squared dist(s.degrees_of_freedom);
  const double p = boost::math::cdf(dist, s.degrees_of_freedom * s.reduced_chi2 / 9);
  if (!(p >= 0.05)) return "";
  return fmt::format(
      ", which {} cannot check: noise three times larger scatters as little {:.0f} % of the "
      "time, so give the frequencies' own uncertainty (--frequency-std)",
      s.degrees_of_freedom == 1 ? "one degree of freedom"
                                : fmt::format("{} degrees of freedom", s.degrees_of_freedom),
      100 * p);
}

}  // namespace

std::string LinearUpdateSummary::report() const {
  static const char* names[] = {"converged",
                                "iteration limit",
                                "no mode paired",
                                "failed",
                                "pairs cannot be decided",
                                "measured shapes refused",
                                "pairs unconfirmed by the shapes"};
  const std::string how =
      status != LinearUpdateStatus::kPairsUnconfirmed
          ? names[static_cast<int>(status)]
          : fmt::format("{} (the fit {})", names[static_cast<int>(status)],
                        fit_converged ? "converged" : "reached its iteration limit");
  std::string out = fmt::format(
      "linear update ({}): {}, {} iterations in {} round{}, cost {:.4g} -> {:.4g}, {} of {} "
      "measured modes paired, largest frequency error {:.3g} %\n",
      rule, how, iterations, rounds, rounds == 1 ? "" : "s", initial_cost, final_cost,
      final.pairing.pairs.size(), final.residuals.size(), 100 * final.max_error());
  if (!ambiguity.empty()) out += fmt::format("  {}\n", ambiguity);
  if (!restarts.empty()) out += fmt::format("  {}\n", restarts);
  if (!shape_problem.empty()) out += fmt::format("  {}\n", shape_problem);
  if (!unconfirmed.empty()) out += fmt::format("  {}\n", unconfirmed);
  out += "  measured  f_exp [Hz]  model mode  f_model [Hz]  error [%]    MAC\n";
  for (Eigen::Index i = 0; i < final.residuals.size(); ++i) {
    const int j = final.pairing.model_for(static_cast<int>(i));
    const double fe = final.measured_frequency_hz(i);
    if (j < 0) {
      out += fmt::format("  {:>8}  {:>10.5g}  unpaired\n", final.measured_id(i), fe);
      continue;
    }
    const std::optional<double> mac = final.pair_mac(i);
    out +=
        fmt::format("  {:>8}  {:>10.5g}  {:>10}  {:>12.5g}  {:>9.3f}  {}\n", final.measured_id(i),
                    fe, j + 1, final.model_frequency_hz(i), 100 * final.residuals(i),
                    mac ? fmt::format("{:.3f}", *mac) : "  -  (no shape)");
  }
  const auto id = [&](Eigen::Index i) { return final.measured_id(i); };
  const std::string noise = stated_noise(frequency_std, mode_frequency_std, id);
  if (noise != stated_noise(frequency_std, Eigen::VectorXd(), id))
    out += fmt::format(
        "  frequency uncertainty: {} (a mode whose files disagree: its residual is divided by its "
        "own, so it weighs less and widens only the sets it fixes)\n",
        noise);
  if (degrees_of_freedom > 0) {
    // Scatter below the 3-sigma level does not make the stated noise right: with few degrees of
    // freedom, noise several times larger often scatters as little.
    const double limit = reduced_chi2_limit(degrees_of_freedom);
    const bool any_fitted = std::any_of(parameters.begin(), parameters.end(),
                                        [](const ParameterReport& p) { return !p.held; });
    out += fmt::format(
        "  reduced chi-square {:.3g} over {} degrees of freedom{}\n", reduced_chi2,
        degrees_of_freedom,
        reduced_chi2 > limit || !any_fitted ? ""
        : reduced_chi2 > 1
            ? fmt::format(" (more than noise of the stated {} gives on average, below {:.3g}, "
                          "its 3-sigma level: the scatter cannot tell whether the noise is that "
                          "or larger, so the standard deviations {})",
                          noise, limit, scatter_widening(*this))
            : fmt::format(" (no more than noise of the stated {} gives; the standard "
                          "deviations assume that noise{})",
                          noise, few_degrees_note(*this)));
  }
  for (const ParameterReport& p : parameters) {
    std::string what;
    if (p.flat)
      what = p.smallest_within_tolerance > 0 ? "  FLAT (not identified by the frequencies)"
                                             : "  FLAT (not identified by the frequencies): held";
    else if (p.held)
      what = "  held";
    else if (!p.acts_with.empty())
      what = fmt::format("  NOT IDENTIFIED alone: acts together with {} (below)",
                         fmt::join(p.acts_with, ", "));
    else if (p.one_sided != 0)
      what = fmt::format("  NOT IDENTIFIED: bounded from {} only (below)",
                         p.one_sided > 0 ? "below" : "above");
    else if (p.relative_std && p.slope_std)
      what = fmt::format(
          "  +/- {:.3g} % (a third of where the chi-square's profile rises by 9; the local "
          "slope's {:.3g} % understates it)",
          100 * *p.relative_std, 100 * *p.slope_std);
    else if (p.relative_std)
      what = fmt::format("  +/- {:.3g} %", 100 * *p.relative_std);
    else if (t_widening == 0)
      what = "  no standard deviation (see the reduced chi-square)";
    // A set held back from where the fit took it is flat there, not here: both are said.
    const std::string drifted = p.drifted_to > 0
                                    ? fmt::format(" here, {:.3g} at {:.6g} where the fit took it",
                                                  p.drifted_sensitivity, p.drifted_to)
                                    : "";
    out += fmt::format("  {}: {:.6g} -> {:.6g}  sensitivity {:.3g}{}{}", p.name, p.start, p.value,
                       p.sensitivity, drifted, what);
    if (p.smallest_within_tolerance > 0) out += "  (smallest within tolerance)";
    out += "\n";
  }
  for (const std::string& w : warnings) out += fmt::format("  WARNING: {}\n", w);
  return out;
}

std::string linear_refusal(const LinearUpdateSummary& summary, const LinearUpdateOptions& options,
                           const std::string& source) {
  if (summary.status == LinearUpdateStatus::kAmbiguous)
    return "the pairs cannot be decided: " + summary.ambiguity;
  if (summary.status == LinearUpdateStatus::kShapesRefused)
    return fmt::format("{}{}", source.empty() ? "" : source + ": ", summary.shape_problem);
  if (summary.status != LinearUpdateStatus::kTooFewPairs) return "";
  return fmt::format(
      "no measured mode{} pairs with a model mode (MAC >= {}, frequency within {:g} %)",
      source.empty() ? "" : " of " + source, options.mac_threshold, 100 * options.frequency_window);
}

}  // namespace jointlab::correlate
