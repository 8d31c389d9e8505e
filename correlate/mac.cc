#include "jointlab/correlate/mac.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>

namespace jointlab::correlate {

double mac(const Eigen::Ref<const Eigen::VectorXcd>& measured,
           const Eigen::Ref<const Eigen::VectorXd>& model) {
  // The model's norm over the measured entries alone: a sensor without an entry (exactly
  // zero: a measured value is never exactly zero) tells nothing of the shape. Counted as a
  // zero, the model's motion there lowered the MAC of exact shapes at two of five sensors to
  // 0.36-0.58, and every pair was refused.
  Eigen::VectorXd y = model;
  for (Eigen::Index k = 0; k < y.size(); ++k) {
    if (measured(k) == std::complex<double>(0.0)) y(k) = 0.0;
  }
  const double xx = measured.squaredNorm();
  const double yy = y.squaredNorm();
  if (xx <= 0.0 || yy <= 0.0) return 0.0;
  return std::norm(measured.dot(y.cast<std::complex<double>>())) / (xx * yy);
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

RealisedShape realise(const Eigen::Ref<const Eigen::VectorXcd>& x) {
  RealisedShape out;
  const double xx = x.squaredNorm();  // x^H x = l1 + l2
  out.shape = x.real();
  if (!(xx > 0)) return out;
  const std::complex<double> xtx = (x.array() * x.array()).sum();  // x^T x, |x^T x| = l1 - l2
  out.phase = 0.5 * std::arg(xtx);
  const Eigen::VectorXcd rotated = x * std::polar(1.0, -out.phase);
  out.shape = rotated.real();
  out.mpc = std::min(1.0, std::norm(xtx) / (xx * xx));
  out.imaginary_share = std::min(1.0, rotated.imag().squaredNorm() / xx);
  Eigen::Index top = 0;
  out.shape.cwiseAbs().maxCoeff(&top);
  if (out.shape(top) < 0) out.shape = -out.shape, out.phase += std::numbers::pi;
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    if (x(k) != std::complex<double>(0.0) && out.shape(k) == 0.0)
      out.shape(k) = std::numeric_limits<double>::min();
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

RulePairing pair_by_rules(const Eigen::Ref<const Eigen::MatrixXd>& mac,
                          const Eigen::Ref<const Eigen::VectorXd>& test_frequency_hz,
                          const std::vector<bool>& has_shape,
                          const Eigen::Ref<const Eigen::VectorXd>& model_frequency_hz,
                          const Eigen::Ref<const Eigen::VectorXd>& model_norm2,
                          const PairingRules& rules, const std::vector<std::string>& test_names) {
  const int rows = static_cast<int>(mac.rows()), cols = static_cast<int>(mac.cols());
  RulePairing out;
  // Visibility against the most visible mode up to twice the highest test frequency.
  const double f_top = rows > 0 ? 2.0 * test_frequency_hz.maxCoeff() : 0.0;
  double top = 0;
  for (int j = 0; j < cols; ++j)
    if (model_frequency_hz(j) <= f_top || top == 0) top = std::max(top, model_norm2(j));
  std::vector<char> visible(cols, 0);
  for (int j = 0; j < cols; ++j) {
    visible[j] = top > 0 && model_norm2(j) >= rules.visibility * top;
    if (!visible[j]) out.hidden.push_back(j);
  }
  auto name = [&](int i) {
    return i < static_cast<int>(test_names.size()) ? test_names[static_cast<size_t>(i)]
                                                   : std::to_string(i + 1);
  };
  auto distance = [&](int i, int j) {
    return std::abs(std::log(model_frequency_hz(j) / test_frequency_hz(i)));
  };
  auto in_window = [&](int i, int j) {
    return model_frequency_hz(j) > 0 &&
           (rules.frequency_window <= 0 ||
            std::abs(model_frequency_hz(j) / test_frequency_hz(i) - 1) <= rules.frequency_window);
  };
  // Sorts candidates nearest in frequency first; true when the nearest is at most half as far
  // (in ln f) as the next, the rule that tells apart candidates the MAC cannot.
  auto nearest_first = [&](int i, std::vector<int>& cand) {
    std::sort(cand.begin(), cand.end(),
              [&](int a, int b) { return distance(i, a) < distance(i, b); });
    return cand.size() < 2 || distance(i, cand[0]) <= 0.5 * distance(i, cand[1]);
  };
  std::vector<char> row_used(rows, 0), col_used(cols, 0);
  // The choice of measured mode i among the free model modes: column, its score, and the
  // ambiguity if frequency cannot decide between candidates of (nearly) equal MAC.
  struct Choice {
    int col = -1;
    double score = -1;
    std::string ambiguity;
    std::vector<int> tied;
  };
  auto choose = [&](int i) {
    Choice c;
    if (!has_shape[i]) {
      // By frequency alone, as for candidates alike at the sensors: the nearest when it is at
      // most half as far in ln f as the next.
      std::vector<int> near;
      for (int j = 0; j < cols; ++j)
        if (!col_used[j] && in_window(i, j)) near.push_back(j);
      if (near.empty()) return c;
      const bool decided = nearest_first(i, near);
      c.col = near.front();
      // After every mode a MAC pairs (scores >= mac_threshold > 0): a MAC of 0.99 is stronger
      // evidence than the nearest frequency. Paired first, a mode seen at one sensor took the
      // partner of a chain mode with MAC 0.99 at 66 Hz (it was at 59.9 Hz, the other at 57.9), and
      // the fit moved ka 36 % off with that mode unpaired.
      c.score = 0.0;
      if (!decided) {
        c.ambiguity = fmt::format(
            "test mode {} ({:.5g} Hz, without a shape the MAC can read: give two sensors or "
            "more): model modes {} ({:.5g} Hz) and {} ({:.5g} Hz) are about as close in "
            "frequency",
            name(i), test_frequency_hz(i), near[0] + 1, model_frequency_hz(near[0]), near[1] + 1,
            model_frequency_hz(near[1]));
        c.tied = {near[0], near[1]};
      }
      return c;
    }
    std::vector<int> cand;
    for (int j = 0; j < cols; ++j)
      if (!col_used[j] && visible[j] && in_window(i, j) && mac(i, j) >= rules.mac_threshold)
        cand.push_back(j);
    if (cand.empty()) return c;
    const double best = mac(i, *std::max_element(cand.begin(), cand.end(), [&](int a, int b) {
                              return mac(i, a) < mac(i, b);
                            }));
    std::vector<int> tied;
    for (int j : cand)
      if (mac(i, j) >= best - rules.tie_mac) tied.push_back(j);
    const bool decided = nearest_first(i, tied);
    c.col = tied.front();
    c.score = mac(i, c.col);
    if (!decided) {
      c.ambiguity = fmt::format(
          "test mode {} ({:.5g} Hz): model modes {} ({:.5g} Hz, MAC {:.3f}) and {} ({:.5g} Hz, "
          "MAC {:.3f}) look alike at the sensors and are about as close in frequency",
          name(i), test_frequency_hz(i), tied[0] + 1, model_frequency_hz(tied[0]), mac(i, tied[0]),
          tied[1] + 1, model_frequency_hz(tied[1]), mac(i, tied[1]));
      c.tied = tied;
    }
    return c;
  };
  while (true) {
    int bi = -1;
    Choice bc;
    for (int i = 0; i < rows; ++i) {
      if (row_used[i]) continue;
      Choice c = choose(i);
      if (c.col >= 0 && c.score > bc.score) bi = i, bc = std::move(c);
    }
    if (bi < 0) break;
    if (!bc.ambiguity.empty()) {
      out.ambiguity += (out.ambiguity.empty() ? "" : "; ") + bc.ambiguity;
      out.ties.push_back({bi, bc.tied});
    }
    row_used[bi] = col_used[bc.col] = 1;
    out.pairing.pairs.push_back({bi, bc.col, mac(bi, bc.col)});
  }
  std::sort(out.pairing.pairs.begin(), out.pairing.pairs.end(),
            [](const ModePair& a, const ModePair& b) { return a.measured < b.measured; });
  for (int i = 0; i < rows; ++i)
    if (!row_used[i]) out.pairing.unpaired_measured.push_back(i);
  for (int j = 0; j < cols; ++j)
    if (!col_used[j]) out.pairing.unpaired_model.push_back(j);
  return out;
}

}  // namespace jointlab::correlate
