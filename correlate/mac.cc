#include "jointlab/correlate/mac.h"

#include <algorithm>

#include <fmt/format.h>

namespace jointlab::correlate {

double mac(const Eigen::Ref<const Eigen::VectorXcd>& measured,
           const Eigen::Ref<const Eigen::VectorXd>& model) {
  const Eigen::VectorXcd y = model.cast<std::complex<double>>();
  const double xx = measured.squaredNorm();
  const double yy = model.squaredNorm();
  if (xx <= 0.0 || yy <= 0.0) return 0.0;
  return std::norm(measured.dot(y)) / (xx * yy);
}

double mac(const Eigen::Ref<const Eigen::VectorXd>& a, const Eigen::Ref<const Eigen::VectorXd>& b) {
  const double aa = a.squaredNorm();
  const double bb = b.squaredNorm();
  if (aa <= 0.0 || bb <= 0.0) return 0.0;
  const double ab = a.dot(b);
  return ab * ab / (aa * bb);
}

Eigen::MatrixXd mac_matrix(const Eigen::Ref<const Eigen::MatrixXcd>& measured,
                           const Eigen::Ref<const Eigen::MatrixXd>& model) {
  Eigen::MatrixXd out(measured.cols(), model.cols());
  for (Eigen::Index i = 0; i < measured.cols(); ++i) {
    for (Eigen::Index j = 0; j < model.cols(); ++j) out(i, j) = mac(measured.col(i), model.col(j));
  }
  return out;
}

int Pairing::model_for(int measured) const {
  for (const ModePair& p : pairs) {
    if (p.measured == measured) return p.model;
  }
  return -1;
}

std::string Pairing::report() const {
  std::string out;
  for (const ModePair& p : pairs) {
    out +=
        fmt::format("measured {} <-> model {} (MAC {:.3f})\n", p.measured + 1, p.model + 1, p.mac);
  }
  for (int i : unpaired_measured) out += fmt::format("measured {} unpaired\n", i + 1);
  return out;
}

Pairing pair_modes(const Eigen::Ref<const Eigen::MatrixXd>& mac_matrix, double threshold) {
  const int rows = static_cast<int>(mac_matrix.rows());
  const int cols = static_cast<int>(mac_matrix.cols());
  std::vector<char> row_used(rows, 0), col_used(cols, 0);
  Pairing out;
  while (true) {
    int bi = -1, bj = -1;
    double best = -1.0;
    for (int i = 0; i < rows; ++i) {
      if (row_used[i]) continue;
      for (int j = 0; j < cols; ++j) {
        if (!col_used[j] && mac_matrix(i, j) > best) {
          best = mac_matrix(i, j);
          bi = i;
          bj = j;
        }
      }
    }
    if (bi < 0 || best < threshold) break;
    row_used[bi] = col_used[bj] = 1;
    out.pairs.push_back({bi, bj, best});
  }
  std::sort(out.pairs.begin(), out.pairs.end(),
            [](const ModePair& a, const ModePair& b) { return a.measured < b.measured; });
  for (int i = 0; i < rows; ++i) {
    if (!row_used[i]) out.unpaired_measured.push_back(i);
  }
  for (int j = 0; j < cols; ++j) {
    if (!col_used[j]) out.unpaired_model.push_back(j);
  }
  return out;
}

}  // namespace jointlab::correlate
