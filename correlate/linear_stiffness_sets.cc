// StiffnessSets: K(theta) = K_0 + sum_k theta_k S_k for named joint element sets
// (linear_update.h).
#include <algorithm>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/correlate/linear_update.h"

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

}  // namespace jointlab::correlate
