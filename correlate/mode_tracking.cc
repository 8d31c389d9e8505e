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
    if (options.interrupt) options.interrupt();
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

namespace {
// MAC_M of mode `j` of `from` with mode `k` of `to` and the modes of `to` within a relative
// `cluster` of its frequency.
double mac_with_cluster(const Eigen::SparseMatrix<double>& mass, const ElasticModes& from, int j,
                        const ElasticModes& to, int k, double cluster) {
  const Eigen::VectorXd mp = mass * from.shapes.col(j);
  const double f = to.frequency_hz(k);
  double sum = 0;
  for (Eigen::Index m = 0; m < to.shapes.cols(); ++m) {
    if (m != k && !(std::abs(to.frequency_hz(m) - f) <= cluster * f)) continue;
    const double c = to.shapes.col(m).dot(mp);
    sum += c * c;
  }
  return sum;
}
}  // namespace

bool same_partners(const Eigen::SparseMatrix<double>& mass, const ElasticModes& a,
                   const std::vector<int>& columns_a, const ElasticModes& b,
                   const std::vector<int>& columns_b, double min_mac, double cluster) {
  if (columns_a.size() != columns_b.size()) return false;
  for (size_t i = 0; i < columns_a.size(); ++i) {
    const int ja = columns_a[i], jb = columns_b[i];
    if ((ja < 0) != (jb < 0)) return false;
    if (ja < 0) continue;
    if (!(mac_with_cluster(mass, a, ja, b, jb, cluster) >= min_mac) ||
        !(mac_with_cluster(mass, b, jb, a, ja, cluster) >= min_mac))
      return false;
  }
  return true;
}

}  // namespace jointlab::correlate
