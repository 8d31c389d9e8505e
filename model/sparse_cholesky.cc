#include "jointlab/model/sparse_cholesky.h"

#include <cassert>

#include <Eigen/CholmodSupport>

namespace jointlab::model {

struct SparseCholesky::Impl {
  Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower> llt;
  Eigen::Index n = 0;
  bool ok = false;
};

SparseCholesky::SparseCholesky() : impl_(std::make_unique<Impl>()) {
  impl_->llt.cholmod().print = 0;  // library code never prints
}
SparseCholesky::~SparseCholesky() = default;
SparseCholesky::SparseCholesky(SparseCholesky&&) noexcept = default;
SparseCholesky& SparseCholesky::operator=(SparseCholesky&&) noexcept = default;

bool SparseCholesky::factorize(const Eigen::SparseMatrix<double>& a) {
  assert(a.rows() == a.cols());
  impl_->llt.setMode(Eigen::CholmodSupernodalLLt);
  impl_->llt.compute(a);
  impl_->n = a.rows();
  impl_->ok = impl_->llt.info() == Eigen::Success;
  return impl_->ok;
}

Eigen::MatrixXd SparseCholesky::solve(const Eigen::MatrixXd& b) const {
  assert(impl_->ok && b.rows() == impl_->n);
  return impl_->llt.solve(b);
}

Eigen::Index SparseCholesky::size() const { return impl_->n; }

}  // namespace jointlab::model
