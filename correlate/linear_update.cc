#include "jointlab/correlate/linear_update.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <ceres/ceres.h>
#include <fmt/format.h>

#include "jointlab/core/error.h"
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

double LinearEvaluation::max_error() const {
  double m = 0;
  for (const ModePair& p : pairing.pairs) m = std::max(m, std::abs(residuals(p.measured)));
  return m;
}

LinearEvaluation evaluate_linear(const StiffnessSets& sets, const model::Model& model,
                                 const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                                 const Eigen::Ref<const Eigen::VectorXd>& theta,
                                 double mac_threshold, double frequency_window) {
  const model::LinearModes modes = model::linear_modes(model.mass, sets.stiffness(theta));
  const int elastic = modes.size() - modes.rigid_count;
  const Eigen::MatrixXd phi = modes.shapes.rightCols(elastic);
  LinearEvaluation e;
  e.model_at_sensors = shapes_at_sensors(sensors, phi);
  e.mac = mac_matrix(measured.shapes, e.model_at_sensors);
  const int m = static_cast<int>(measured.frequency_hz.size());
  e.all_model_frequency_hz.resize(elastic);
  for (int j = 0; j < elastic; ++j)
    e.all_model_frequency_hz(j) = modes.frequency_hz(modes.rigid_count + j);
  Eigen::MatrixXd candidates = e.mac;
  // A measured mode without a shape pairs with the nearest model frequency.
  for (int i = 0; i < m; ++i) {
    if (measured.shapes.col(i).squaredNorm() > 0 || elastic == 0) continue;
    Eigen::Index nearest = 0;
    (e.all_model_frequency_hz.array() - measured.frequency_hz(i)).abs().minCoeff(&nearest);
    candidates.row(i).setZero();
    candidates(i, nearest) = 1;
  }
  if (frequency_window > 0) {
    for (int i = 0; i < m; ++i) {
      for (int j = 0; j < elastic; ++j) {
        const double d = e.all_model_frequency_hz(j) / measured.frequency_hz(i) - 1;
        if (std::abs(d) > frequency_window) candidates(i, j) = 0;
      }
    }
  }
  e.pairing = pair_modes(candidates, mac_threshold);
  e.measured_frequency_hz = measured.frequency_hz;
  e.model_frequency_hz = Eigen::VectorXd::Zero(m);
  e.residuals = Eigen::VectorXd::Zero(m);
  e.jacobian = Eigen::MatrixXd::Zero(m, sets.size());
  for (const ModePair& p : e.pairing.pairs) {
    const double f = e.all_model_frequency_hz(p.model);
    const double fe = measured.frequency_hz(p.measured);
    e.model_frequency_hz(p.measured) = f;
    e.residuals(p.measured) = (f - fe) / fe;
    if (f <= 0) continue;
    const Eigen::VectorXd v = phi.col(p.model);
    for (int k = 0; k < sets.size(); ++k) {
      const double dw2 = v.dot(sets.pattern(k) * v);
      e.jacobian(p.measured, k) =
          theta(k) * dw2 / (8.0 * std::numbers::pi * std::numbers::pi * f * fe);
    }
  }
  return e;
}

std::string LinearUpdateOptions::error() const {
  if (!(mac_threshold >= 0 && mac_threshold <= 1)) return "mac_threshold must be in [0, 1]";
  if (!(lower_factor > 0 && lower_factor < 1)) return "lower_factor must be in (0, 1)";
  if (!(upper_factor > 1) || !std::isfinite(upper_factor)) return "upper_factor must be > 1";
  if (max_iterations < 1) return "max_iterations must be >= 1";
  if (!(tolerance >= 0)) return "tolerance must be >= 0";
  if (!(flat_sensitivity > 0)) return "flat_sensitivity must be > 0";
  if (!(frequency_std > 0)) return "frequency_std must be > 0";
  if (!(sweep_decades > 0)) return "sweep_decades must be > 0";
  if (sweep_points < 2) return "sweep_points must be >= 2";
  if (!(frequency_window >= 0)) return "frequency_window must be >= 0";
  if (!(alias_mac > 0 && alias_mac <= 1)) return "alias_mac must be in (0, 1]";
  for (const ParameterBound& b : bounds) {
    if (!(b.lower > 0 && b.lower < b.upper) || !std::isfinite(b.upper)) {
      return fmt::format("bounds of '{}': need 0 < lower < upper", b.name);
    }
  }
  if (rule == LinearRule::kSmallest) {
    if (!(tolerance > 0)) return "the smallest rule needs a tolerance > 0";
    if (smallest_set.empty()) return "the smallest rule needs the set to minimise";
  }
  return "";
}

namespace {

// Ceres cost on x = ln theta with the analytic Jacobian of evaluate_linear().
class LinearCost : public ceres::CostFunction {
 public:
  LinearCost(const StiffnessSets& sets, const model::Model& model,
             const std::vector<Sensor>& sensors, const MeasuredModes& measured, double threshold,
             double window)
      : sets_(sets),
        model_(model),
        sensors_(sensors),
        measured_(measured),
        threshold_(threshold),
        window_(window) {
    set_num_residuals(static_cast<int>(measured.frequency_hz.size()));
    mutable_parameter_block_sizes()->push_back(sets.size());
  }
  bool Evaluate(double const* const* x, double* residuals, double** jacobians) const override {
    const int n = sets_.size();
    Eigen::VectorXd theta(n);
    for (int k = 0; k < n; ++k) theta(k) = std::exp(x[0][k]);
    LinearEvaluation e;
    try {
      e = evaluate_linear(sets_, model_, sensors_, measured_, theta, threshold_, window_);
    } catch (const InputError&) {
      return false;  // an indefinite K at this step: the optimiser shrinks its step
    }
    const int m = num_residuals();
    for (int i = 0; i < m; ++i) residuals[i] = e.residuals(i);
    if (jacobians && jacobians[0]) {
      for (int i = 0; i < m; ++i) {
        for (int k = 0; k < n; ++k) jacobians[0][i * n + k] = e.jacobian(i, k);
      }
    }
    return true;
  }

 private:
  const StiffnessSets& sets_;
  const model::Model& model_;
  const std::vector<Sensor>& sensors_;
  const MeasuredModes& measured_;
  double threshold_, window_;
};

// Records the objective and every stiffness after each iteration (the paper's Table 1).
class ProgressCallback : public ceres::IterationCallback {
 public:
  ProgressCallback(const std::function<void(int, double)>& f, const Eigen::VectorXd& x,
                   LinearUpdateSummary* s)
      : f_(f), x_(x), s_(s) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& it) override {
    if (s_) {
      s_->history.push_back(it.cost);
      s_->theta_history.push_back(x_.array().exp());
    }
    if (f_) f_(it.iteration, it.cost);
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const std::function<void(int, double)>& f_;
  const Eigen::VectorXd& x_;
  LinearUpdateSummary* s_;
};

double rms_error(const LinearEvaluation& e) {
  if (e.pairing.pairs.empty()) return 0;
  return std::sqrt(e.residuals.squaredNorm() / static_cast<double>(e.pairing.pairs.size()));
}

}  // namespace

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

void check_measured(const std::vector<Sensor>& sensors, const MeasuredModes& measured) {
  if (measured.shapes.rows() != static_cast<Eigen::Index>(sensors.size()) ||
      measured.shapes.cols() != measured.frequency_hz.size()) {
    throw InputError(fmt::format(
        "measured modes: {} shapes of {} sensors for {} frequencies, expected {} sensors",
        measured.shapes.cols(), measured.shapes.rows(), measured.frequency_hz.size(),
        sensors.size()));
  }
  for (Eigen::Index i = 0; i < measured.frequency_hz.size(); ++i) {
    if (!(measured.frequency_hz(i) > 0) || !std::isfinite(measured.frequency_hz(i))) {
      throw InputError(fmt::format("measured mode {}: frequency must be > 0", i + 1));
    }
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

// The updating problem: the sets, the data, the options and the bounds of each set.
struct LinearProblem {
  const StiffnessSets& sets;
  const model::Model& model;
  const std::vector<std::string>& names;
  const std::vector<Sensor>& sensors;
  const MeasuredModes& measured;
  const LinearUpdateOptions& options;
  Eigen::VectorXd start, lower, upper;

  int size() const { return sets.size(); }

  LinearEvaluation evaluate(const Eigen::VectorXd& theta) const {
    return evaluate_linear(sets, model, sensors, measured, theta, options.mac_threshold,
                           options.frequency_window);
  }

  // Least squares over the sets not held, from x (ln theta), in the bounds.
  ceres::TerminationType fit(Eigen::VectorXd& x, int held, LinearUpdateSummary* record) const {
    const int n = size();
    ceres::Problem problem;
    problem.AddResidualBlock(new LinearCost(sets, model, sensors, measured, options.mac_threshold,
                                            options.frequency_window),
                             nullptr, x.data());
    for (int k = 0; k < n; ++k) {
      problem.SetParameterLowerBound(x.data(), k, std::log(lower(k)));
      problem.SetParameterUpperBound(x.data(), k, std::log(upper(k)));
    }
    if (held >= 0) {
      if (n == 1) return ceres::CONVERGENCE;
      problem.SetManifold(x.data(), new ceres::SubsetManifold(n, {held}));
    }
    ceres::Solver::Options so;
    so.max_num_iterations = options.max_iterations;
    so.linear_solver_type = ceres::DENSE_QR;
    so.function_tolerance = 1e-12;
    so.gradient_tolerance = 1e-14;
    so.parameter_tolerance = 1e-10;
    so.update_state_every_iteration = true;
    ProgressCallback cb(options.progress, x, record);
    so.callbacks.push_back(&cb);
    ceres::Solver::Summary cs;
    ceres::Solve(so, &problem, &cs);
    if (record) record->iterations += static_cast<int>(cs.iterations.size()) - 1;
    return cs.termination_type;
  }
};

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
  LinearProblem p{sets, model, names, sensors, measured, options, sets.initial(), {}, {}};
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

// Per set at the optimum: sensitivity, flat or not, and the standard deviation of the
// identifiable sets from (J^T J)^{-1} sigma_f^2.
void report_identifiability(const LinearProblem& p, const LinearEvaluation& at,
                            LinearUpdateSummary& s) {
  const int n = p.size();
  s.parameters.resize(n);
  std::vector<int> identifiable;
  for (int k = 0; k < n; ++k) {
    ParameterReport& r = s.parameters[k];
    r.name = p.names[k];
    r.start = p.start(k);
    r.lower = p.lower(k);
    r.upper = p.upper(k);
    r.sensitivity = at.jacobian.col(k).cwiseAbs().maxCoeff();
    r.flat = r.sensitivity < p.options.flat_sensitivity;
    if (!r.flat) identifiable.push_back(k);
  }
  if (identifiable.empty()) return;
  Eigen::MatrixXd j(at.jacobian.rows(), static_cast<Eigen::Index>(identifiable.size()));
  for (size_t c = 0; c < identifiable.size(); ++c) j.col(c) = at.jacobian.col(identifiable[c]);
  const Eigen::MatrixXd jtj = j.transpose() * j;
  Eigen::LDLT<Eigen::MatrixXd> ldlt(jtj);
  const double sf = p.options.frequency_std;
  const Eigen::MatrixXd cov =
      ldlt.solve(Eigen::MatrixXd::Identity(jtj.rows(), jtj.cols())) * (sf * sf);
  for (size_t c = 0; c < identifiable.size(); ++c) {
    const double v = cov(c, c);
    s.parameters[identifiable[c]].relative_std = (v >= 0 && std::isfinite(v)) ? std::sqrt(v) : 0;
  }
}

// Within the tolerance: every pair of `at` kept, every paired error at most the tolerance.
auto within_tolerance(const LinearProblem& p, const LinearEvaluation& at) {
  return [&p, pairs = at.pairing.pairs.size()](const LinearEvaluation& e) {
    return e.pairing.pairs.size() == pairs && e.max_error() <= p.options.tolerance;
  };
}

// The paper's rule: the smallest theta_k with the others fitted and every error within the
// tolerance; x, theta and at move to it.
void smallest_rule(const LinearProblem& p, int k, Eigen::VectorXd& x, Eigen::VectorXd& theta,
                   LinearEvaluation& at, LinearUpdateSummary& s) {
  const auto within = within_tolerance(p, at);
  if (!within(at)) {
    s.tolerance_met = false;
    s.warnings.push_back(
        fmt::format("the tolerance {:.3g} % cannot be met: the least-squares fit leaves a largest "
                    "frequency error of {:.3g} %; kept the least-squares result",
                    100 * p.options.tolerance, 100 * at.max_error()));
    return;
  }
  // feasible(v): fit the others at theta_k = v from the last feasible point.
  Eigen::VectorXd best = x;
  auto feasible = [&](double v) {
    Eigen::VectorXd trial = best;
    trial(k) = v;
    p.fit(trial, k, nullptr);
    try {
      if (!within(p.evaluate(trial.array().exp()))) return false;
    } catch (const InputError&) {
      return false;
    }
    best = trial;
    s.history.push_back(p.evaluate(trial.array().exp()).cost());
    s.theta_history.push_back(trial.array().exp());
    return true;
  };
  double hi = x(k), lo = std::log(p.lower(k));
  if (feasible(lo)) {
    hi = lo;
  } else {
    // ln theta to 1e-3: theta_m within 0.1 % of the smallest feasible value.
    for (int it = 0; it < 60 && hi - lo > 1e-3; ++it) {
      const double mid = 0.5 * (lo + hi);
      (feasible(mid) ? hi : lo) = mid;
    }
  }
  x = best;
  theta = x.array().exp();
  s.parameters[k].smallest_within_tolerance = theta(k);
  at = p.evaluate(theta);
}

// The smallest stiffness within the tolerance for each flat set, the others held.
void smallest_flat(const LinearProblem& p, Eigen::VectorXd& theta, LinearEvaluation& at,
                   LinearUpdateSummary& s) {
  const auto within = within_tolerance(p, at);
  for (int k = 0; k < p.size(); ++k) {
    if (!s.parameters[k].flat) continue;
    auto ok = [&](double v) {
      Eigen::VectorXd t = theta;
      t(k) = v;
      try {
        return within(p.evaluate(t));
      } catch (const InputError&) {
        return false;
      }
    };
    if (!ok(theta(k))) continue;
    double hi = std::log(theta(k));
    double lo = std::log(p.lower(k));
    if (ok(std::exp(lo))) {
      hi = lo;
    } else {
      for (int it = 0; it < 40 && hi - lo > 1e-4; ++it) {
        const double mid = 0.5 * (lo + hi);
        (ok(std::exp(mid)) ? hi : lo) = mid;
      }
    }
    theta(k) = std::exp(hi);
    s.parameters[k].smallest_within_tolerance = theta(k);
  }
  at = p.evaluate(theta);
}

// Warns of every set that ends at a bound.
void warn_bounds(const LinearProblem& p, const Eigen::VectorXd& theta, LinearUpdateSummary& s) {
  for (int k = 0; k < p.size(); ++k) {
    ParameterReport& r = s.parameters[k];
    const double lx = std::log(theta(k));
    if (lx <= std::log(p.lower(k)) + 1e-6) r.at_bound = -1;
    if (lx >= std::log(p.upper(k)) - 1e-6) r.at_bound = 1;
    if (r.at_bound != 0) {
      s.warnings.push_back(fmt::format(
          "{} ends at its {} bound {:.6g}: widen the bounds or hold it", r.name,
          r.at_bound < 0 ? "lower" : "upper", r.at_bound < 0 ? p.lower(k) : p.upper(k)));
    }
  }
}

// Warns of model modes the sensors cannot tell apart (among modes up to 1.5 x the highest
// measured).
void warn_aliased(const LinearProblem& p, const LinearEvaluation& at, LinearUpdateSummary& s) {
  const double f_top = 1.5 * p.measured.frequency_hz.maxCoeff();
  Eigen::Index count = 0;
  while (count < at.all_model_frequency_hz.size() && at.all_model_frequency_hz(count) <= f_top)
    ++count;
  for (const AliasedModes& a :
       aliased_modes(at.model_at_sensors.leftCols(count), p.options.alias_mac)) {
    s.warnings.push_back(fmt::format(
        "model modes {} ({:.4g} Hz) and {} ({:.4g} Hz) look alike at the sensors (auto-MAC "
        "{:.3f}): MAC cannot tell them apart, the frequency window must",
        a.a + 1, at.all_model_frequency_hz(a.a), a.b + 1, at.all_model_frequency_hz(a.b), a.mac));
  }
}

// One-at-a-time sweeps around the result.
void sweeps(const LinearProblem& p, const Eigen::VectorXd& theta, LinearUpdateSummary& s) {
  const LinearUpdateOptions& o = p.options;
  for (int k = 0; k < p.size(); ++k) {
    ParameterReport& r = s.parameters[k];
    r.value = theta(k);
    for (int i = 0; i < o.sweep_points; ++i) {
      const double d = -o.sweep_decades + 2.0 * o.sweep_decades * i / (o.sweep_points - 1);
      const double f = std::pow(10.0, d);
      Eigen::VectorXd t = theta;
      t(k) *= f;
      try {
        const LinearEvaluation e = p.evaluate(t);
        r.sweep_factor.push_back(f);
        r.sweep_rms.push_back(rms_error(e));
        r.sweep_errors.push_back(e.residuals);
      } catch (const InputError&) {
      }
    }
  }
}

LinearUpdateStatus status_of(ceres::TerminationType tt) {
  if (tt == ceres::CONVERGENCE) return LinearUpdateStatus::kConverged;
  if (tt == ceres::NO_CONVERGENCE) return LinearUpdateStatus::kIterationLimit;
  return LinearUpdateStatus::kFailed;
}

}  // namespace

Eigen::VectorXd update_linear(const model::Model& model, const std::vector<std::string>& names,
                              const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                              const LinearUpdateOptions& options, LinearUpdateSummary* summary) {
  if (const std::string e = options.error(); !e.empty()) throw InputError("update-linear: " + e);
  check_measured(sensors, measured);
  const StiffnessSets sets(model, names);
  const LinearProblem p = make_problem(sets, model, names, sensors, measured, options);
  const int minimised = options.rule == LinearRule::kSmallest
                            ? set_index(names, options.smallest_set, "the smallest rule")
                            : -1;
  LinearUpdateSummary local;
  LinearUpdateSummary& s = summary ? *summary : local;
  s = LinearUpdateSummary{};

  // The start, clamped into the bounds.
  const Eigen::VectorXd begin = p.start.cwiseMax(p.lower).cwiseMin(p.upper);
  const LinearEvaluation first = p.evaluate(begin);
  s.initial_cost = first.cost();
  if (first.pairing.pairs.empty()) {
    s.status = LinearUpdateStatus::kTooFewPairs;
    s.final_cost = s.initial_cost;
    s.final = first;
    return begin;
  }

  Eigen::VectorXd x = begin.array().log();
  s.status = status_of(p.fit(x, -1, &s));
  Eigen::VectorXd theta = x.array().exp();
  LinearEvaluation at = p.evaluate(theta);
  report_identifiability(p, at, s);
  if (options.rule == LinearRule::kSmallest) {
    smallest_rule(p, minimised, x, theta, at, s);
  } else if (options.tolerance > 0) {
    smallest_flat(p, theta, at, s);
  }
  warn_bounds(p, theta, s);
  warn_aliased(p, at, s);
  sweeps(p, theta, s);
  s.final_cost = at.cost();
  s.final_mac = at.mac;
  s.final = std::move(at);
  return theta;
}

std::string LinearUpdateSummary::report() const {
  static const char* names[] = {"converged", "iteration limit", "no mode paired", "failed"};
  std::string out = fmt::format(
      "linear update: {}, {} iterations, cost {:.4g} -> {:.4g}, {} of {} measured modes paired, "
      "largest frequency error {:.3g} %\n",
      names[static_cast<int>(status)], iterations, initial_cost, final_cost,
      final.pairing.pairs.size(), final.residuals.size(), 100 * final.max_error());
  out += "  measured  f_exp [Hz]  model mode  f_model [Hz]  error [%]    MAC\n";
  for (Eigen::Index i = 0; i < final.residuals.size(); ++i) {
    const int j = final.pairing.model_for(static_cast<int>(i));
    const double fe = final.measured_frequency_hz(i);
    if (j < 0) {
      out += fmt::format("  {:>8}  {:>10.5g}  unpaired\n", i + 1, fe);
      continue;
    }
    out += fmt::format("  {:>8}  {:>10.5g}  {:>10}  {:>12.5g}  {:>9.3f}  {:.3f}\n", i + 1, fe,
                       j + 1, final.model_frequency_hz(i), 100 * final.residuals(i),
                       final.mac.size() > 0 ? final.mac(i, j) : 0.0);
  }
  for (const ParameterReport& p : parameters) {
    out += fmt::format("  {}: {:.6g} -> {:.6g}  sensitivity {:.3g}{}", p.name, p.start, p.value,
                       p.sensitivity,
                       p.flat ? "  FLAT (not identified by the frequencies)"
                              : fmt::format("  +/- {:.3g} %", 100 * p.relative_std));
    if (p.smallest_within_tolerance > 0) out += "  (smallest within tolerance)";
    out += "\n";
  }
  for (const std::string& w : warnings) out += fmt::format("  WARNING: {}\n", w);
  return out;
}

}  // namespace jointlab::correlate
