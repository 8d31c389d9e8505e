// Fitted sets acting together (linear_collinear.h).
#include "jointlab/correlate/linear_collinear.h"

#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>

namespace jointlab::correlate::detail {
namespace {

// A singular value of the fitted sets' Jacobian with unit columns whose square is below this
// marks sets acting together: for two sets, a correlation of their sensitivities above 0.999.
constexpr double kCollinearSquared = 1e-3;

}  // namespace

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

}  // namespace jointlab::correlate::detail
