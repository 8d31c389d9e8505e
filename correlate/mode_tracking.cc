#include "jointlab/correlate/mode_tracking.h"

#include <algorithm>
#include <cassert>

#include "jointlab/model/linear_modes.h"

namespace jointlab::correlate {

ElasticModes elastic_modes(const Eigen::SparseMatrix<double>& mass,
                           const Eigen::SparseMatrix<double>& stiffness) {
  const model::LinearModes modes = model::linear_modes(mass, stiffness);
  const int elastic = modes.size() - modes.rigid_count;
  ElasticModes out;
  out.shapes = modes.shapes.rightCols(elastic);
  out.frequency_hz.resize(elastic);
  for (int j = 0; j < elastic; ++j) out.frequency_hz(j) = modes.frequency_hz(modes.rigid_count + j);
  return out;
}

std::vector<int> follow_modes(const Eigen::Ref<const Eigen::MatrixXd>& before,
                              const Eigen::Ref<const Eigen::MatrixXd>& after,
                              const Eigen::SparseMatrix<double>& mass,
                              const std::vector<int>& tracked, const TrackingOptions& options,
                              std::vector<double>* mac) {
  assert(before.rows() == after.rows() && before.rows() == mass.rows());
  std::vector<int> out(tracked.size(), -1);
  if (mac) mac->assign(tracked.size(), 0.0);
  for (size_t t = 0; t < tracked.size(); ++t) {
    if (tracked[t] < 0) continue;
    // (a^T M b)^2 for every new shape b at once.
    const Eigen::VectorXd ma = mass * before.col(tracked[t]);
    const Eigen::VectorXd m = (after.transpose() * ma).array().square();
    Eigen::Index best = 0;
    const double top = after.cols() > 0 ? m.maxCoeff(&best) : 0.0;
    double second = 0;
    for (Eigen::Index j = 0; j < m.size(); ++j)
      if (j != best) second = std::max(second, m(j));
    if (mac) (*mac)[t] = top;
    if (top >= options.min_mac && top - second >= options.margin) out[t] = static_cast<int>(best);
  }
  return out;
}

std::optional<FollowedModes> follow_path(
    const std::function<Eigen::SparseMatrix<double>(double)>& stiffness,
    const Eigen::SparseMatrix<double>& mass, const ElasticModes& start,
    const std::vector<int>& tracked, const TrackingOptions& options) {
  FollowedModes now{start, tracked, 0};
  const double base = 1.0 / std::max(1, options.substeps);
  const double smallest = base / static_cast<double>(1 << std::clamp(options.max_halvings, 0, 30));
  double s = 0, h = base;
  while (s < 1.0) {
    const double next = std::min(1.0, s + h);
    ElasticModes trial = elastic_modes(mass, stiffness(next));
    ++now.solves;
    std::vector<int> cols;
    if (trial.shapes.cols() > 0)
      cols = follow_modes(now.modes.shapes, trial.shapes, mass, now.columns, options);
    bool ok = trial.shapes.cols() > 0;
    for (size_t t = 0; ok && t < cols.size(); ++t) ok = now.columns[t] < 0 || cols[t] >= 0;
    // Two tracked modes never continue as one.
    for (size_t a = 0; ok && a < cols.size(); ++a)
      for (size_t b = a + 1; ok && b < cols.size(); ++b) ok = cols[a] < 0 || cols[a] != cols[b];
    if (!ok) {
      if (h <= smallest * 1.5) return std::nullopt;
      h *= 0.5;
      continue;
    }
    now.modes = std::move(trial);
    now.columns = std::move(cols);
    s = next;
    h = std::min(base, 2 * h);
  }
  return now;
}

}  // namespace jointlab::correlate
