// The updating problem (linear_problem.h): its points, pairs followed by shape, and the
// least-squares fit over the sets not held.
#include "jointlab/correlate/linear_problem.h"

#include <algorithm>
#include <cmath>

#include <ceres/ceres.h>
#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/model/linear_modes.h"

namespace jointlab::correlate::detail {
namespace {

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

}  // namespace

// The index of `name` among the sets updated; InputError "`what`: ..." if it is not one.
int set_index(const std::vector<std::string>& names, const std::string& name,
              const std::string& what) {
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) {
    throw InputError(fmt::format("{}: '{}' is not one of the sets updated", what, name));
  }
  return static_cast<int>(it - names.begin());
}

PairingRules LinearProblem::rules() const {
  PairingRules r;
  r.mac_threshold = options.mac_threshold;
  r.frequency_window = options.frequency_window;
  r.visibility = options.visibility;
  return r;
}

Eigen::VectorXd LinearProblem::begin() const {
  Eigen::VectorXd x = start.cwiseMax(lower).cwiseMin(upper);
  for (const ParameterHold& h : options.holds)
    if (h.value > 0) x(set_index(names, h.name, "hold")) = h.value;
  return x;
}

TrackedPoint LinearProblem::fresh(const Eigen::VectorXd& x, LinearEvaluation& e) const {
  if (options.interrupt) options.interrupt();
  const Eigen::VectorXd theta = x.array().exp();
  TrackedPoint p{x, elastic_modes(model.mass, sets.stiffness(theta)), {}};
  e = evaluate_by_rules(sets, sensors, measured, theta, p.modes, rules(), p.columns);
  e.weights = weight;
  return p;
}

std::optional<TrackedPoint> LinearProblem::move(const TrackedPoint& from, const Eigen::VectorXd& x,
                                                int substeps) const {
  if (x == from.x) return from;
  TrackingOptions t = tracking;
  t.substeps = substeps;
  t.interrupt = options.interrupt;  // before each of its eigen-solves
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

LinearEvaluation LinearProblem::evaluate(const TrackedPoint& p) const {
  LinearEvaluation e =
      evaluate_pairs(sets, sensors, measured, p.x.array().exp(), p.modes, p.columns);
  e.weights = weight;
  return e;
}

Eigen::MatrixXd LinearProblem::weighted_jacobian(const LinearEvaluation& e) const {
  return weight.asDiagonal() * e.jacobian;
}
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

LinearUpdateStatus status_of(ceres::TerminationType tt) {
  if (tt == ceres::CONVERGENCE) return LinearUpdateStatus::kConverged;
  if (tt == ceres::NO_CONVERGENCE) return LinearUpdateStatus::kIterationLimit;
  return LinearUpdateStatus::kFailed;
}

bool fitted(const LinearUpdateSummary& s) {
  return s.status == LinearUpdateStatus::kConverged ||
         s.status == LinearUpdateStatus::kIterationLimit;
}

std::string pair_text(const LinearEvaluation& e, int i) {
  const int j = e.pairing.model_for(i);
  if (j < 0) return "unpaired";
  return fmt::format("model mode {} ({:.5g} Hz, MAC {:.3f})", j + 1, e.all_model_frequency_hz(j),
                     e.mac(i, j));
}

}  // namespace jointlab::correlate::detail
