// The Iwan objective's linear limit: the frequencies mode R can reach over K_T, and the measured
// linear modes' errors at given parameters and along K_T.
#include <algorithm>
#include <cmath>
#include <optional>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/correlate/iwan_objective.h"
#include "jointlab/correlate/mode_tracking.h"
#include "jointlab/model/linear_modes.h"

namespace jointlab::correlate {

Eigen::Vector2d IwanObjective::frequency_reach(int mode, double gamma) const {
  model::Model m = *model_;
  Eigen::Vector2d out(NAN, NAN);
  try {
    const model::LinearModes as_given = model::linear_modes(m.mass, m.linear_stiffness());
    const int col = as_given.rigid_count + mode - 1;  // the same ordered eigenvalue in both
    for (int side = 0; side < 2; ++side) {
      for (model::Joint& j : m.joints)
        if (j.element == set_) j.stiffness = side == 0 ? 0.0 : gamma * Ks_;
      const model::LinearModes lm = model::linear_modes(m.mass, m.linear_stiffness());
      if (col < lm.size()) out(side) = std::max(lm.frequency_hz(col), 0.0);
    }
  } catch (const InputError&) {
    return Eigen::Vector2d(NAN, NAN);
  }
  return out;
}

std::string unreachable_frequencies(const IwanObjective& objective,
                                    const IwanUpdateOptions& options) {
  const double gamma = options.fixed_gamma > 0 ? options.fixed_gamma : options.bounds.gamma_max;
  const double kt = gamma * objective.reference_stiffness();
  std::string out;
  for (const IwanTarget& t : objective.targets()) {
    double lo = INFINITY, hi = 0;
    for (const MeasuredBackbone& c : t.curves) {
      lo = std::min(lo, c.frequency_hz.minCoeff());
      hi = std::max(hi, c.frequency_hz.maxCoeff());
    }
    const Eigen::Vector2d reach = objective.frequency_reach(t.mode, gamma);
    if (!reach.allFinite()) continue;
    const std::string stuck =
        fmt::format("stuck at K_T = {:.4g} x K_s = {:.6g} N/m ({})", gamma, kt,
                    options.fixed_gamma > 0 ? "--gamma" : "the top of the gamma range");
    std::string e;
    if (lo > reach(1)) {
      e = fmt::format(
          "mode {}: every measured frequency ({:.6g} to {:.6g} Hz) lies above {:.6g} Hz, the "
          "highest model mode {} reaches (every element of the set {}; slipped, it falls to "
          "{:.6g} Hz)",
          t.mode, lo, hi, reach(1), t.mode, stuck, reach(0));
    } else if (hi < reach(0)) {
      e = fmt::format(
          "mode {}: every measured frequency ({:.6g} to {:.6g} Hz) lies below {:.6g} Hz, the "
          "lowest model mode {} reaches (every element of the set slipped, no stiffness; {}, it "
          "rises to {:.6g} Hz)",
          t.mode, lo, hi, reach(0), t.mode, stuck, reach(1));
    }
    if (!e.empty()) out += (out.empty() ? "" : "; ") + e;
  }
  if (!out.empty()) {
    out +=
        ": no Iwan parameters in the bounds can fit these backbones; check the model's linear "
        "part (update-linear), the mode and the frequency column";
  }
  return out;
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

std::vector<std::vector<std::optional<double>>> IwanObjective::linear_errors_along(
    const std::vector<double>& gammas) const {
  const size_t m = static_cast<size_t>(linear_modes_.frequency_hz.size());
  std::vector<std::vector<std::optional<double>>> out(gammas.size());
  if (m == 0) return out;
  const StiffnessSets sets(*model_, {set_});
  const double k0 = sets.initial()(0);
  PairingRules rules;
  rules.mac_threshold = linear_mac_;
  const Eigen::VectorXd theta0 = Eigen::VectorXd::Constant(1, k0);
  const LinearEvaluation at0 =
      evaluate_linear(sets, *model_, sensors_, linear_modes_, theta0, rules);
  std::vector<int> columns(m, -1);
  for (const ModePair& q : at0.pairing.pairs) columns[static_cast<size_t>(q.measured)] = q.model;
  const ElasticModes modes0 = elastic_modes(model_->mass, sets.stiffness(theta0));
  // Walk up from gamma = 1 through the larger gammas in ascending order, then down through the
  // smaller ones in descending order.
  std::vector<size_t> order(gammas.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return gammas[a] < gammas[b]; });
  auto walk = [&](const std::vector<size_t>& along) {
    ElasticModes now = modes0;
    std::vector<int> cols = columns;
    double g_now = 1.0;
    for (size_t i : along) {
      const double g = gammas[i];
      const double a = std::log(g_now), b = std::log(g);
      TrackingOptions t;
      t.substeps = std::max(1, static_cast<int>(std::ceil(std::abs(b - a) / 0.05)));
      const auto path = [&](double s) {
        return sets.stiffness(Eigen::VectorXd::Constant(1, k0 * std::exp(a + s * (b - a))));
      };
      std::optional<FollowedModes> f;
      try {
        f = follow_path(path, model_->mass, now, cols, t);
      } catch (const InputError&) {
      }
      if (!f) return;  // lost: this gamma and those beyond have no followed pairs
      now = std::move(f->modes);
      cols = std::move(f->columns);
      g_now = g;
      const LinearEvaluation e = evaluate_pairs(sets, sensors_, linear_modes_,
                                                Eigen::VectorXd::Constant(1, k0 * g), now, cols);
      out[i].resize(m);
      for (const ModePair& q : e.pairing.pairs)
        out[i][static_cast<size_t>(q.measured)] = e.residuals(q.measured);
    }
  };
  std::vector<size_t> up, down;
  for (size_t i : order) (gammas[i] >= 1.0 ? up : down).push_back(i);
  std::reverse(down.begin(), down.end());
  walk(up);
  walk(down);
  for (auto& v : out) v.resize(m);
  return out;
}

}  // namespace jointlab::correlate
