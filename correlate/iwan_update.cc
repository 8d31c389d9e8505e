#include "jointlab/correlate/iwan_update.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>

#include <ceres/ceres.h>
#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/core/parallel.h"
#include "jointlab/correlate/qsma_at.h"
#include "jointlab/model/joint_condensation.h"
#include "jointlab/model/linear_modes.h"
#include "jointlab/model/qsma.h"

namespace jointlab::correlate {
namespace {

constexpr double kPenalty = 1e6;  // cost of a parameter set the model cannot evaluate
constexpr int kBatch = 50;        // samples evaluated between two progress reports

}  // namespace

int amplitude_power(AmplitudeQuantity q) {
  return q == AmplitudeQuantity::kDisplacement ? 0 : q == AmplitudeQuantity::kVelocity ? 1 : 2;
}

IwanBounds default_iwan_bounds(const model::IwanParameters& start) {
  IwanBounds b;
  b.Fs_min = start.Fs / 30;
  b.Fs_max = start.Fs * 30;
  b.gamma_min = 0.05;
  b.gamma_max = 2;
  b.chi_min = -0.95;
  b.chi_max = 0;
  b.beta_min = 0.01;
  b.beta_max = 100;
  return b;
}

std::string IwanUpdateOptions::error() const {
  const IwanBounds& b = bounds;
  if (!(b.Fs_min > 0 && b.Fs_min < b.Fs_max)) return "bounds: 0 < Fs_min < Fs_max";
  if (!(b.gamma_min > 0 && b.gamma_min < b.gamma_max)) return "bounds: 0 < gamma_min < gamma_max";
  if (!(b.chi_min > -1 && b.chi_min < b.chi_max)) return "bounds: -1 < chi_min < chi_max";
  if (!(b.beta_min > 0 && b.beta_min < b.beta_max)) return "bounds: 0 < beta_min < beta_max";
  if (!(fixed_gamma >= 0)) return "fixed_gamma must be >= 0";
  if (fixed_beta && !(*fixed_beta >= 0 && std::isfinite(*fixed_beta)))
    return "fixed_beta must be a finite number >= 0";
  if (samples < 2) return "samples must be >= 2";
  if (!(contraction > 0 && contraction < 1)) return "contraction must be in (0, 1)";
  if (max_evaluations < samples) return "max_evaluations must be >= samples";
  if (local_starts < 1) return "local_starts must be >= 1";
  if (threads < 0) return "threads must be >= 0 (0: every core)";
  if (!(frequency_floor > 0) || !(damping_floor > 0)) return "floors must be > 0";
  return "";
}

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
      comparison_(options.comparison) {
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
      if (c.sensor < 0 || c.sensor >= static_cast<int>(sensors_.size())) {
        throw InputError(fmt::format("mode {}: backbone sensor index out of range", t.mode));
      }
      const Eigen::Index n = c.amplitude.size();
      if (n == 0 || c.frequency_hz.size() != n || c.damping_ratio.size() != n ||
          c.frequency_std_hz.size() != n || c.damping_std.size() != n) {
        throw InputError(
            fmt::format("mode {}, channel {}: backbone columns empty or of unequal "
                        "length",
                        t.mode, sensors_[c.sensor].channel));
      }
      if ((c.amplitude.array() <= 0).any() || (c.frequency_hz.array() <= 0).any() ||
          !c.amplitude.allFinite() || !c.frequency_hz.allFinite() || !c.damping_ratio.allFinite()) {
        throw InputError(
            fmt::format("mode {}, channel {}: amplitudes and frequencies must be "
                        "finite and > 0",
                        t.mode, sensors_[c.sensor].channel));
      }
      residual_count_ += 2 * static_cast<int>(n);
      residual_curve_.insert(residual_curve_.end(), 2 * static_cast<size_t>(n), curve_index++);
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

Eigen::Vector2d IwanObjective::slip_range(const model::IwanParameters& p) const {
  std::vector<double> r(residual_count_);
  Eigen::Vector2d slip(INFINITY, 0);
  return evaluate(p, r.data(), &slip, false) ? slip : Eigen::Vector2d::Zero();
}

bool IwanObjective::evaluate(const model::IwanParameters& p, double* r, Eigen::Vector2d* slip_range,
                             bool from_scratch) const {
  ++evaluations_;
  if (!model::iwan_parameter_error(p).empty()) return false;
  const int pw = amplitude_power(amplitude_);
  const double n_total = residual_count_ / 2.0;
  try {
    std::optional<model::JointCondensation> shared;
    if (!from_scratch && set_model_) shared = set_model_->at(p);
    const model::JointCondensation& jc = shared ? *shared : shared.emplace(apply(p));
    const model::LinearModes& modes = jc.modes();
    int k = 0;
    for (const IwanTarget& t : targets_) {
      if (t.mode > jc.elastic_count()) return false;
      const int col = modes.rigid_count + t.mode - 1;
      // Every point of every curve of this target on one QSMA curve: s = a / |phi_R[d]|.
      std::vector<std::pair<double, std::pair<size_t, Eigen::Index>>> order;
      for (size_t ci = 0; ci < t.curves.size(); ++ci) {
        const MeasuredBackbone& c = t.curves[ci];
        // A mode that leaves the sensor still (to rounding: 1e-8 of its largest motion) is
        // not the one measured there.
        const double ph = std::abs(modes.shapes(sensors_[c.sensor].dof, col));
        if (!(ph > 1e-8 * modes.shapes.col(col).cwiseAbs().maxCoeff())) return false;
        for (Eigen::Index j = 0; j < c.amplitude.size(); ++j)
          order.push_back({c.amplitude(j) / ph, {ci, j}});
      }
      std::sort(order.begin(), order.end());
      std::vector<double> s(order.size());
      for (size_t i = 0; i < order.size(); ++i) s[i] = order[i].first;
      const bool matched = comparison_ == IwanComparison::kMatched;
      const std::vector<QsmaAtPoint> at =
          qsma_at(jc, t.mode, pw, s,
                  matched ? AmplitudeFrequency::kFirstHarmonic : AmplitudeFrequency::kSecant,
                  from_scratch ? QsmaAtSolver::kBracketing : QsmaAtSolver::kNewton);
      if (at.size() != s.size()) return false;
      if (slip_range) {
        (*slip_range)(0) = std::min((*slip_range)(0), at.front().point.max_slip);
        (*slip_range)(1) = std::max((*slip_range)(1), at.back().point.max_slip);
      }
      // Residuals in the order of the curves and their points.
      std::vector<std::vector<const model::QsmaPoint*>> model_at(t.curves.size());
      for (size_t ci = 0; ci < t.curves.size(); ++ci)
        model_at[ci].resize(static_cast<size_t>(t.curves[ci].amplitude.size()));
      for (size_t i = 0; i < order.size(); ++i)
        model_at[order[i].second.first][static_cast<size_t>(order[i].second.second)] = &at[i].point;
      for (size_t ci = 0; ci < t.curves.size(); ++ci) {
        const MeasuredBackbone& c = t.curves[ci];
        for (Eigen::Index j = 0; j < c.amplitude.size(); ++j) {
          const model::QsmaPoint& q = *model_at[ci][static_cast<size_t>(j)];
          const double f = matched ? q.ringdown_frequency_hz : q.frequency_hz;
          const double z = !matched                               ? q.damping_ratio
                           : c.kind == BackboneKind::kSteppedSine ? q.harmonic_damping_ratio
                                                                  : q.ringdown_damping_ratio;
          const double sf = std::max(c.frequency_std_hz(j), f_floor_ * c.frequency_hz(j));
          const double sz = std::max(c.damping_std(j), z_floor_ * std::abs(c.damping_ratio(j)));
          r[k++] = (f - c.frequency_hz(j)) / (sf * std::sqrt(n_total));
          r[k++] = sz > 0 ? (z - c.damping_ratio(j)) / (sz * std::sqrt(n_total)) : 0.0;
        }
      }
    }
  } catch (const InputError&) {
    return false;
  }
  for (int i = 0; i < residual_count_; ++i) {
    if (!std::isfinite(r[i])) return false;
  }
  return true;
}

double IwanObjective::cost(const model::IwanParameters& p) const {
  std::vector<double> r(residual_count_);
  if (!residuals(p, r.data())) return kPenalty;
  double s = 0;
  for (double v : r) s += v * v;
  return std::min(s, kPenalty);
}

double IwanObjective::linear_error(const model::IwanParameters& p) const {
  const model::Model m = apply(p);
  const model::LinearModes modes = model::linear_modes(m.mass, m.linear_stiffness());
  double e = 0;
  for (const IwanTarget& t : targets_) {
    if (!(t.linear_frequency_hz > 0)) continue;
    const int col = modes.rigid_count + t.mode - 1;
    if (col >= modes.size()) continue;
    e = std::max(e,
                 std::abs(modes.frequency_hz(col) - t.linear_frequency_hz) / t.linear_frequency_hz);
  }
  return e;
}

void IwanObjective::set_linear_modes(const MeasuredModes& measured, double mac_threshold) {
  if (measured.shapes.rows() != static_cast<Eigen::Index>(sensors_.size()) ||
      measured.shapes.cols() != measured.frequency_hz.size()) {
    throw InputError("measured linear modes: shapes do not match the sensors and frequencies");
  }
  linear_modes_ = measured;
  linear_mac_ = mac_threshold;
}

std::vector<std::optional<double>> IwanObjective::linear_errors(
    const model::IwanParameters& p) const {
  std::vector<std::optional<double>> out;
  if (linear_modes_.frequency_hz.size() == 0) return out;
  const model::Model m = apply(p);
  const StiffnessSets none(m, {});
  const LinearEvaluation e =
      evaluate_linear(none, m, sensors_, linear_modes_, Eigen::VectorXd::Zero(0), linear_mac_);
  out.resize(static_cast<size_t>(linear_modes_.frequency_hz.size()));
  for (const ModePair& q : e.pairing.pairs)
    out[static_cast<size_t>(q.measured)] = e.residuals(q.measured);
  return out;
}

namespace {

// The search vector v = (F_S, gamma, chi, beta).
using Vec4 = Eigen::Vector4d;

model::IwanParameters to_params(const Vec4& v, double Ks) { return {v(0), v(1) * Ks, v(2), v(3)}; }

// Evaluations with bookkeeping: history, best, budget, progress.
struct Tracker {
  const IwanObjective& objective;
  const IwanUpdateOptions& options;
  IwanUpdateSummary& summary;
  int start_evaluations;
  Vec4 best_v = Vec4::Zero();
  double best = INFINITY;

  int used() const { return objective.evaluations() - start_evaluations; }
  bool spent() const { return used() >= options.max_evaluations; }
  void record(const Vec4& v, double c) { record(v, c, used()); }
  void record(const Vec4& v, double c, int evaluation) {
    if (c < best) {
      best = c;
      best_v = v;
    }
    summary.history.push_back({evaluation, c, best});
    if (options.progress) options.progress(evaluation, best);
  }
  // Costs of vs (evaluated on options.threads threads, each independent of the others), then
  // recorded in their order: the outcome does not depend on the number of threads.
  std::vector<double> eval(const std::vector<Vec4>& vs) {
    std::vector<double> c(vs.size());
    const int base = used();
    parallel_for(
        vs.size(), static_cast<unsigned>(options.threads), [] { return 0; },
        [&](size_t i, int) {
          c[i] = objective.cost(to_params(vs[i], objective.reference_stiffness()));
        });
    for (size_t i = 0; i < vs.size(); ++i) record(vs[i], c[i], base + static_cast<int>(i) + 1);
    return c;
  }
};

struct Box {
  Vec4 lo, hi;
};

Vec4 sample(const Box& b, bool log_scale, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Vec4 v;
  for (int i = 0; i < 4; ++i) {
    const double t = u(rng);
    const bool lg = log_scale && i != 2 && b.lo(i) > 0;
    v(i) = lg ? std::exp(std::log(b.lo(i)) + t * (std::log(b.hi(i)) - std::log(b.lo(i))))
              : b.lo(i) + t * (b.hi(i) - b.lo(i));
  }
  return v;
}

// Which of (F_S, gamma, chi, beta) the options hold at a given value.
std::array<bool, 4> held_parameters(const IwanUpdateOptions& o) {
  return {false, o.fixed_gamma > 0, false, o.fixed_beta.has_value()};
}

Box initial_box(const IwanUpdateOptions& o) {
  const IwanBounds& b = o.bounds;
  Box box{Vec4(b.Fs_min, b.gamma_min, b.chi_min, b.beta_min),
          Vec4(b.Fs_max, b.gamma_max, b.chi_max, b.beta_max)};
  if (o.fixed_gamma > 0) box.lo(1) = box.hi(1) = o.fixed_gamma;
  if (o.fixed_beta) box.lo(3) = box.hi(3) = *o.fixed_beta;
  return box;
}

void monte_carlo(Tracker& tr, bool log_scale, std::mt19937& rng) {
  const Box full = initial_box(tr.options);
  Box box = full;
  double previous = INFINITY;
  while (!tr.spent()) {
    const int n = std::min(tr.options.samples, tr.options.max_evaluations - tr.used());
    for (int done = 0; done < n;) {
      std::vector<Vec4> vs;
      for (; done < n && static_cast<int>(vs.size()) < kBatch; ++done)
        vs.push_back(sample(box, log_scale, rng));
      tr.eval(vs);
    }
    ++tr.summary.rounds;
    if (!(tr.best < previous)) {
      tr.summary.status = IwanUpdateStatus::kConverged;
      return;
    }
    previous = tr.best;
    for (int i = 0; i < 4; ++i) {
      const double d = tr.options.contraction * std::max(std::abs(tr.best_v(i)), 1e-3);
      box.lo(i) = std::max(full.lo(i), tr.best_v(i) - d);
      box.hi(i) = std::min(full.hi(i), tr.best_v(i) + d);
    }
  }
  tr.summary.status = IwanUpdateStatus::kBudget;
}

// x = (ln F_S, ln gamma, chi, ln beta).
Vec4 to_x(const Vec4& v) { return Vec4(std::log(v(0)), std::log(v(1)), v(2), std::log(v(3))); }
Vec4 to_v(const double* x) { return Vec4(std::exp(x[0]), std::exp(x[1]), x[2], std::exp(x[3])); }

// Residuals with central-difference Jacobians (QSMA is not templated on the scalar). Not
// ceres::NumericDiffCostFunction: its step is |x| times a relative size, which vanishes for
// ln gamma and ln beta near 0, where the 1e-10 accuracy of qsma_at would swamp the difference;
// a fixed step of 1e-4 in x keeps that error near 1e-6 of the derivative.
class IwanCost : public ceres::CostFunction {
 public:
  IwanCost(Tracker& tr, std::array<bool, 4> held) : tr_(tr), held_(held) {
    set_num_residuals(tr.objective.residual_count());
    mutable_parameter_block_sizes()->push_back(4);
  }
  bool Evaluate(double const* const* x, double* r, double** jac) const override {
    const double Ks = tr_.objective.reference_stiffness();
    const Vec4 v = with_held(to_v(x[0]));
    if (!tr_.objective.residuals(to_params(v, Ks), r)) {
      tr_.record(v, kPenalty);
      return false;
    }
    double c = 0;
    for (int i = 0; i < num_residuals(); ++i) c += r[i] * r[i];
    tr_.record(v, c);
    if (!jac || !jac[0]) return true;
    const int m = num_residuals();
    // The 2 x 4 shifted residual vectors, each independent: on the option's threads.
    const double h = 1e-4;
    std::vector<std::vector<double>> shifted(8, std::vector<double>(m));
    std::array<char, 8> ok{};
    parallel_for(
        8, static_cast<unsigned>(tr_.options.threads), [] { return 0; },
        [&](size_t j, int) {
          const int k = static_cast<int>(j / 2);
          if (held_[k]) return;
          double xs[4];
          std::copy(x[0], x[0] + 4, xs);
          xs[k] += j % 2 == 0 ? h : -h;
          ok[j] = tr_.objective.residuals(to_params(with_held(to_v(xs)), Ks), shifted[j].data());
        });
    for (int k = 0; k < 4; ++k) {
      if (held_[k]) {
        for (int i = 0; i < m; ++i) jac[0][i * 4 + k] = 0;
        continue;
      }
      if (!ok[2 * k] || !ok[2 * k + 1]) return false;
      const std::vector<double>&rp = shifted[2 * k], &rm = shifted[2 * k + 1];
      for (int i = 0; i < m; ++i) jac[0][i * 4 + k] = (rp[i] - rm[i]) / (2 * h);
    }
    return true;
  }

 private:
  // v with the held parameters at their values: their coordinates in x are placeholders (ln 0
  // of beta held at 0 is no finite coordinate).
  Vec4 with_held(Vec4 v) const {
    const IwanUpdateOptions& o = tr_.options;
    if (held_[1]) v(1) = o.fixed_gamma;
    if (held_[3]) v(3) = *o.fixed_beta;
    return v;
  }

  Tracker& tr_;
  std::array<bool, 4> held_;
};

class BudgetCallback : public ceres::IterationCallback {
 public:
  BudgetCallback(const Tracker& tr, int limit) : tr_(tr), limit_(limit) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    return tr_.used() >= limit_ ? ceres::SOLVER_TERMINATE_SUCCESSFULLY : ceres::SOLVER_CONTINUE;
  }

 private:
  const Tracker& tr_;
  int limit_;
};

void global_local(Tracker& tr, std::mt19937& rng) {
  const IwanUpdateOptions& o = tr.options;
  const Box full = initial_box(o);
  std::vector<std::pair<double, Vec4>> samples;
  const int n_global =
      std::min(std::max(o.samples, o.max_evaluations / 2), o.max_evaluations - tr.used());
  for (int done = 0; done < n_global;) {
    std::vector<Vec4> vs;
    for (; done < n_global && static_cast<int>(vs.size()) < kBatch; ++done)
      vs.push_back(sample(full, true, rng));
    const std::vector<double> c = tr.eval(vs);
    for (size_t i = 0; i < vs.size(); ++i) samples.emplace_back(c[i], vs[i]);
  }
  std::sort(samples.begin(), samples.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  const std::array<bool, 4> held = held_parameters(o);
  std::vector<int> constant;
  for (int k = 0; k < 4; ++k)
    if (held[k]) constant.push_back(k);
  bool converged = true;
  for (int s = 0; s < o.local_starts && s < static_cast<int>(samples.size()); ++s) {
    if (samples[s].first >= kPenalty) break;
    const int remaining = o.max_evaluations - tr.used();
    if (remaining <= 9) break;
    const int limit = tr.used() + remaining / (o.local_starts - s);
    Vec4 x = to_x(samples[s].second);
    for (int k = 0; k < 4; ++k)
      if (held[k]) x(k) = 0;  // a placeholder (IwanCost uses the held values)
    ceres::Problem problem;
    problem.AddResidualBlock(new IwanCost(tr, held), nullptr, x.data());
    const Vec4 lo = to_x(full.lo), hi = to_x(full.hi);
    if (!constant.empty()) problem.SetManifold(x.data(), new ceres::SubsetManifold(4, constant));
    for (int k = 0; k < 4; ++k) {
      if (held[k]) continue;
      problem.SetParameterLowerBound(x.data(), k, lo(k));
      problem.SetParameterUpperBound(x.data(), k, hi(k));
    }
    ceres::Solver::Options so;
    so.linear_solver_type = ceres::DENSE_QR;
    so.max_num_iterations = 50;
    so.function_tolerance = 1e-10;
    so.parameter_tolerance = 1e-8;
    BudgetCallback cb(tr, limit);
    so.callbacks.push_back(&cb);
    ceres::Solver::Summary cs;
    ceres::Solve(so, &problem, &cs);
    ++tr.summary.rounds;
    if (cs.termination_type != ceres::CONVERGENCE) converged = false;
  }
  tr.summary.status = converged ? IwanUpdateStatus::kConverged : IwanUpdateStatus::kBudget;
}

// Covariance of x = (ln F_S, ln gamma, chi, ln beta) at v (ln gamma and ln K_T differ by a
// constant); 0 rows and columns for held parameters, all 0 when unknown.
// Gauss-Newton: (J^T J)^-1 / N (residuals are normalised by sigma sqrt(N)) times the reduced
// chi-square. With G >= 3 curves also the cluster-robust covariance H^-1 (G/(G-1) sum_c g_c
// g_c^T) H^-1, H = J^T J, g_c = J_c^T r_c over curve c's residuals: points along one hit's
// backbone share that hit's offset, so the curves, not the points, are the independent samples;
// each variance is then the larger of the two (G - 1 degrees of freedom estimate the spread
// between curves poorly when G is small), with the cluster-robust correlations.
Eigen::Matrix4d covariance(const IwanObjective& objective, const IwanUpdateOptions& options,
                           const Vec4& v) {
  const std::array<bool, 4> held = held_parameters(options);
  std::vector<int> free;
  for (int k = 0; k < 4; ++k)
    if (!held[k]) free.push_back(k);
  const int m = objective.residual_count(), nf = static_cast<int>(free.size());
  const double Ks = objective.reference_stiffness();
  Eigen::MatrixXd J(m, nf);
  Eigen::VectorXd r(m);
  std::vector<double> rp(m), rm(m);
  if (!objective.residuals(to_params(v, Ks), r.data())) return Eigen::Matrix4d::Zero();
  const Vec4 x0 = to_x(v);
  for (int j = 0; j < nf; ++j) {
    const double h = 1e-4;
    Vec4 xp = x0, xm = x0;
    xp(free[j]) += h;
    xm(free[j]) -= h;
    if (!objective.residuals(to_params(to_v(xp.data()), Ks), rp.data()) ||
        !objective.residuals(to_params(to_v(xm.data()), Ks), rm.data())) {
      return Eigen::Matrix4d::Zero();
    }
    for (int i = 0; i < m; ++i) J(i, j) = (rp[i] - rm[i]) / (2 * h);
  }
  const Eigen::MatrixXd H = J.transpose() * J;
  Eigen::FullPivLU<Eigen::MatrixXd> lu(H);
  if (!lu.isInvertible()) return Eigen::Matrix4d::Zero();
  const Eigen::MatrixXd Hi = lu.inverse();
  const std::vector<int>& curve = objective.residual_curve();
  const int n_curves = curve.empty() ? 0 : curve.back() + 1;
  // Gauss-Newton: (J^T J)^-1 / N scaled by the reduced chi-square (about 1 in the scatter).
  const double chi2 = r.squaredNorm() * (m / 2.0) / std::max(1, m - nf);
  Eigen::MatrixXd cov = Hi / (m / 2.0) * chi2;
  if (n_curves >= 3) {
    Eigen::MatrixXd g = Eigen::MatrixXd::Zero(nf, n_curves);
    for (int i = 0; i < m; ++i) g.col(curve[i]) += J.row(i).transpose() * r(i);
    const Eigen::MatrixXd B = g * g.transpose() * (n_curves / (n_curves - 1.0));
    const Eigen::MatrixXd robust = Hi * B * Hi;
    // Few curves estimate the scatter between them poorly (G - 1 degrees of freedom): each
    // variance is the larger of the two, with the cluster-robust correlations.
    Eigen::VectorXd d(nf);
    bool usable = true;
    for (int k = 0; k < nf; ++k) {
      usable = usable && robust(k, k) > 0;
      d(k) = robust(k, k) > 0 ? std::sqrt(std::max(1.0, cov(k, k) / robust(k, k))) : 0.0;
    }
    if (usable) cov = d.asDiagonal() * robust * d.asDiagonal();
  }
  if (!cov.allFinite()) return Eigen::Matrix4d::Zero();
  Eigen::Matrix4d out = Eigen::Matrix4d::Zero();
  for (int i = 0; i < nf; ++i)
    for (int j = 0; j < nf; ++j) out(free[i], free[j]) = cov(i, j);
  return out;
}

// The free parameters of v that end within 1e-3 of their range (in the search coordinates x)
// of a bound, e.g. "Fs at its upper bound 2000 N".
std::vector<std::string> bounds_reached(const IwanUpdateOptions& options, const Vec4& v) {
  const Box box = initial_box(options);
  const Vec4 x = to_x(v), lo = to_x(box.lo), hi = to_x(box.hi);
  static const char* names[] = {"Fs", "gamma (Kt/Ks)", "chi", "beta"};
  static const char* units[] = {" N", "", "", ""};
  std::vector<std::string> out;
  for (int k = 0; k < 4; ++k) {
    if (!(hi(k) > lo(k))) continue;  // held
    const double tol = 1e-3 * (hi(k) - lo(k));
    if (x(k) <= lo(k) + tol) {
      out.push_back(fmt::format("{} at its lower bound {:.6g}{}", names[k], box.lo(k), units[k]));
    } else if (x(k) >= hi(k) - tol) {
      out.push_back(fmt::format("{} at its upper bound {:.6g}{}", names[k], box.hi(k), units[k]));
    }
  }
  return out;
}

void set_slips(const IwanObjective& objective, IwanUpdateSummary& s) {
  const Eigen::Vector2d slip = objective.slip_range(s.best);
  s.bottom_slip = slip(0);
  s.top_slip = slip(1);
  s.phi_max = model::Iwan(s.best).phi_max();
}

}  // namespace

model::IwanParameters update_iwan(const IwanObjective& objective, const IwanUpdateOptions& options,
                                  IwanUpdateSummary* summary) {
  if (const std::string e = options.error(); !e.empty()) throw InputError("update-iwan: " + e);
  IwanUpdateSummary local;
  IwanUpdateSummary& s = summary ? *summary : local;
  s = IwanUpdateSummary{};
  s.optimizer = options.optimizer;
  s.start = objective.initial();
  Tracker tr{objective, options, s, objective.evaluations()};
  s.initial_cost = objective.cost(s.start);
  std::mt19937 rng(options.seed);
  switch (options.optimizer) {
    case IwanOptimizer::kPaper:
      monte_carlo(tr, false, rng);
      break;
    case IwanOptimizer::kPaperLog:
      monte_carlo(tr, true, rng);
      break;
    case IwanOptimizer::kGlobalLocal:
      global_local(tr, rng);
      break;
  }
  s.evaluations = tr.used();
  // The start with the held parameters at their held values: K_T = gamma K_s as asked.
  model::IwanParameters start = s.start;
  if (options.fixed_gamma > 0) start.Kt = options.fixed_gamma * objective.reference_stiffness();
  if (options.fixed_beta) start.beta = *options.fixed_beta;
  if (!(tr.best < kPenalty)) {
    s.status = IwanUpdateStatus::kNoValidPoint;
    s.best = start;
    s.final_cost = objective.cost(start);
    return start;
  }
  // The start is a candidate too when it lies in the search box (held parameters at their
  // values): never hand back parameters that fit worse, nor any outside the given ranges.
  const Box box = initial_box(options);
  const double Ks = objective.reference_stiffness();
  const Vec4 start_v(start.Fs, start.Kt / Ks, start.chi, start.beta);
  bool start_inside = true;
  for (int k = 0; k < 4; ++k) {
    const double slack = 1e-12 * std::max(std::abs(box.lo(k)), std::abs(box.hi(k)));
    start_inside =
        start_inside && start_v(k) >= box.lo(k) - slack && start_v(k) <= box.hi(k) + slack;
  }
  const double start_cost = !start_inside ? INFINITY
                            : start.Kt == s.start.Kt && start.beta == s.start.beta
                                ? s.initial_cost
                                : objective.cost(start);
  if (start_cost <= tr.best) {
    s.improved = false;
    s.best = start;
    s.final_cost = start_cost;
    s.linear_error = objective.linear_error(s.best);
    set_slips(objective, s);
    return s.best;
  }
  // Inside the box also after the round trip through the search coordinates (exp(log(60))
  // is 59.99999999999999).
  tr.best_v = tr.best_v.cwiseMax(box.lo).cwiseMin(box.hi);
  s.best = to_params(tr.best_v, Ks);
  s.final_cost = tr.best;
  s.at_bounds = bounds_reached(options, tr.best_v);
  s.linear_error = objective.linear_error(s.best);
  s.covariance = covariance(objective, options, tr.best_v);
  for (int k = 0; k < 4; ++k) {
    const double sd = std::sqrt(std::max(s.covariance(k, k), 0.0));
    s.relative_std(k) = k != 2 ? sd : std::abs(s.best.chi) > 0 ? sd / std::abs(s.best.chi) : 0.0;
  }
  set_slips(objective, s);
  return s.best;
}

std::string IwanUpdateSummary::report() const {
  static const char* names[] = {"converged", "evaluation budget spent", "no valid sample"};
  std::string out = fmt::format(
      "Iwan update: {}, {} QSMA evaluations, {} rounds, cost {:.4g} -> {:.4g}, linear frequency "
      "error {:.3g} %\n  Fs {:.6g} -> {:.6g} N, Kt {:.6g} -> {:.6g} N/m, chi {:.4g} -> {:.4g}, "
      "beta {:.4g} -> {:.4g}\n",
      status == IwanUpdateStatus::kConverged && !at_bounds.empty()
          ? "stopped at a bound of the search range"
          : names[static_cast<int>(status)],
      evaluations, rounds, initial_cost, final_cost, 100 * linear_error, start.Fs, best.Fs,
      start.Kt, best.Kt, start.chi, best.chi, start.beta, best.beta);
  if (!improved || status == IwanUpdateStatus::kNoValidPoint) {
    out += fmt::format(
        "  no sample improved on the start: the result is the start{}. {}\n",
        status == IwanUpdateStatus::kNoValidPoint ? " (no sample could be evaluated)" : "",
        optimizer == IwanOptimizer::kGlobalLocal
            ? "Widen the bounds or give a better start."
            : "The Monte Carlo's uniform samples rarely land near the optimum in wide bounds: "
              "use the global-local optimiser (--optimizer global-local).");
  }
  if (!at_bounds.empty()) {
    std::string which;
    for (const std::string& b : at_bounds) which += (which.empty() ? "" : ", ") + b;
    out += fmt::format(
        "  the fit ends at a bound: {}; the best fit may lie outside the range, widen it\n", which);
  }
  if (relative_std.any()) {
    out += fmt::format(
        "  one-sigma relative uncertainty: Fs {:.2g} %, Kt {:.2g} %, chi {:.2g} %, beta {:.2g} % "
        "(0: held or unknown)\n",
        100 * relative_std(0), 100 * relative_std(1), 100 * relative_std(2), 100 * relative_std(3));
  }
  if (top_slip > 0 && phi_max > 0) {
    out += fmt::format(
        "  largest joint slip {:.3g} to {:.3g} m over the measured amplitudes, phi_max {:.3g} m: "
        "{}\n",
        bottom_slip, top_slip, phi_max,
        microslip_only() ? "microslip only, Fs and beta are not identified separately"
                         : "the data reach macroslip");
  }
  return out;
}

std::vector<ParetoPoint> pareto_front(const IwanObjective& objective,
                                      const std::vector<double>& gammas,
                                      const IwanUpdateOptions& options) {
  std::vector<ParetoPoint> out;
  for (double g : gammas) {
    if (!(g > 0)) throw InputError(fmt::format("Pareto front: gamma {} must be > 0", g));
    IwanUpdateOptions o = options;
    o.fixed_gamma = g;
    IwanUpdateSummary s;
    ParetoPoint p;
    p.gamma = g;
    p.params = update_iwan(objective, o, &s);
    if (s.status == IwanUpdateStatus::kNoValidPoint) {
      throw InputError(fmt::format(
          "Pareto front: at gamma {} (K_T = {:.6g} N/m) no parameter set in the bounds gives a "
          "QSMA curve over the measured amplitudes",
          g, g * objective.reference_stiffness()));
    }
    p.linear_error = s.linear_error;
    p.mode_errors = objective.linear_errors(p.params);
    p.backbone_cost = s.final_cost;
    out.push_back(p);
  }
  for (ParetoPoint& a : out) {
    for (const ParetoPoint& b : out) {
      if (&a != &b && b.linear_error <= a.linear_error && b.backbone_cost <= a.backbone_cost &&
          (b.linear_error < a.linear_error || b.backbone_cost < a.backbone_cost)) {
        a.dominated = true;
      }
    }
  }
  return out;
}

}  // namespace jointlab::correlate
