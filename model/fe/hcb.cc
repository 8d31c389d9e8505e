#include "jointlab/model/fe/hcb.h"

#include <algorithm>
#include <cassert>
#include <functional>

#include <fmt/format.h>
#include <Eigen/Dense>

#include "jointlab/model/sparse_cholesky.h"
#include "jointlab/model/sparse_eigen.h"

namespace jointlab::model::fe {
namespace {

using SpMat = Eigen::SparseMatrix<double>;

// Rows `rows` and columns `cols` of a (selection by permutation-like sparse products).
SpMat select(const SpMat& a, const SpMat& pick_rows, const SpMat& pick_cols) {
  return pick_rows * a * pick_cols;
}

// The |idx| × n selection matrix S with (S x)_k = x_idx[k].
SpMat selector(const std::vector<int>& idx, int n) {
  std::vector<Eigen::Triplet<double>> t;
  for (int k = 0; k < static_cast<int>(idx.size()); ++k) t.emplace_back(k, idx[k], 1.0);
  SpMat s(static_cast<Eigen::Index>(idx.size()), n);
  s.setFromTriplets(t.begin(), t.end());
  return s;
}

// K and M split into interior (i) and boundary (b) blocks.
struct Partition {
  SpMat k_ii, k_ib, k_bb, m_ii, m_ib, m_bb;
  Partition(const SpMat& k, const SpMat& m, const std::vector<int>& boundary) {
    const int n = static_cast<int>(k.rows());
    std::vector<char> is_b(static_cast<size_t>(n), 0);
    for (int b : boundary) {
      assert(b >= 0 && b < n && !is_b[static_cast<size_t>(b)]);
      is_b[static_cast<size_t>(b)] = 1;
    }
    std::vector<int> interior;
    for (int i = 0; i < n; ++i)
      if (!is_b[static_cast<size_t>(i)]) interior.push_back(i);
    const SpMat sb = selector(boundary, n), si = selector(interior, n);
    const SpMat sbt = sb.transpose(), sit = si.transpose();
    k_ii = select(k, si, sit);
    k_ib = select(k, si, sbt);
    k_bb = select(k, sb, sbt);
    m_ii = select(m, si, sit);
    m_ib = select(m, si, sbt);
    m_bb = select(m, sb, sbt);
  }
  int boundary_dofs() const { return static_cast<int>(k_bb.rows()); }
  int interior_dofs() const { return static_cast<int>(k_ii.rows()); }
};

// The constraint modes Psi = -K_ii^-1 K_ib, one solve of every boundary DOF: CHOLMOD's solve of
// blocks of them gave other roundings (entries of the example's reduced K and M 1e-16 of the
// largest apart, one more exact zero), so `interrupt` is heard before it only.
Eigen::MatrixXd constraint_modes(const SparseCholesky& factor, const SpMat& k_ib,
                                 const std::function<void()>& interrupt) {
  if (interrupt) interrupt();
  return -factor.solve(Eigen::MatrixXd(k_ib));
}

// The reduced K and M on [boundary DOFs; fixed-interface modes phi (eigenvalues lambda)] with
// the constraint modes psi, into out->stiffness and out->mass.
void project(const Partition& p, const Eigen::MatrixXd& psi, const Eigen::MatrixXd& phi,
             const Eigen::VectorXd& lambda, HcbReduction* out) {
  const Eigen::Index nb = psi.cols(), nm = phi.cols();
  Eigen::MatrixXd kbb_r = Eigen::MatrixXd(p.k_bb) + Eigen::MatrixXd(p.k_ib.transpose() * psi);
  const Eigen::MatrixXd mii_psi_mib = p.m_ii * psi + Eigen::MatrixXd(p.m_ib);
  Eigen::MatrixXd mbb_r = Eigen::MatrixXd(p.m_bb) + psi.transpose() * mii_psi_mib +
                          Eigen::MatrixXd(p.m_ib.transpose() * psi);
  kbb_r = 0.5 * (kbb_r + kbb_r.transpose()).eval();
  mbb_r = 0.5 * (mbb_r + mbb_r.transpose()).eval();
  const Eigen::MatrixXd mqb = phi.transpose() * mii_psi_mib;  // nm x nb

  const Eigen::Index nr = nb + nm;
  Eigen::MatrixXd kr = Eigen::MatrixXd::Zero(nr, nr), mr = Eigen::MatrixXd::Zero(nr, nr);
  kr.topLeftCorner(nb, nb) = kbb_r;
  mr.topLeftCorner(nb, nb) = mbb_r;
  for (Eigen::Index j = 0; j < nm; ++j) {
    kr(nb + j, nb + j) = lambda(j);
    mr(nb + j, nb + j) = 1.0;
  }
  mr.bottomLeftCorner(nm, nb) = mqb;
  mr.topRightCorner(nb, nm) = mqb.transpose();
  out->stiffness = kr.sparseView();
  out->mass = mr.sparseView();
}

}  // namespace

std::string HcbOptions::validate() const {
  if (fixed_interface_modes < 0) return "fixed_interface_modes must be >= 0";
  if (!(tolerance > 0)) return "tolerance must be positive";
  return "";
}

HcbReduction reduce_hcb(const SpMat& k, const SpMat& m, const std::vector<int>& boundary,
                        const HcbOptions& options) {
  assert(options.validate().empty());
  const auto say = [&](const std::string& s) {
    if (options.progress) options.progress(s);
  };
  const Partition p(k, m, boundary);
  const int n = static_cast<int>(k.rows()), nb = p.boundary_dofs(), ni = p.interior_dofs();
  HcbReduction out;
  out.boundary = boundary;
  out.summary.boundary_dofs = nb;
  out.summary.interior_dofs = ni;

  say(fmt::format("factorising K_ii ({} interior DOFs, {} nonzeros)", ni, p.k_ii.nonZeros()));
  SparseCholesky factor;
  if (!factor.factorize(p.k_ii)) {
    out.summary.status = HcbStatus::kInteriorNotPositiveDefinite;
    out.summary.report = fmt::format(
        "K_ii ({} interior DOFs) is not positive definite: the {} boundary DOFs do not "
        "restrain every part of the structure",
        ni, nb);
    return out;
  }

  const int nm = std::min(options.fixed_interface_modes, ni);
  Eigen::MatrixXd phi(ni, 0);
  out.interface_eigenvalues.resize(0);
  std::string eig_report = "no fixed-interface modes";
  if (nm > 0) {
    say(fmt::format("fixed-interface modes: {} lowest by shift-invert Lanczos", nm));
    EigenOptions eo;
    eo.count = nm;
    eo.shift = 0;
    eo.tolerance = options.tolerance;
    eo.interrupt = options.interrupt;
    const EigenResult er = lowest_modes(factor, p.m_ii, eo);
    eig_report = er.summary.report;
    if (!er.summary.ok()) {
      out.summary.status = HcbStatus::kEigenNotConverged;
      out.summary.report = "fixed-interface eigen-solve failed: " + er.summary.report;
      return out;
    }
    phi = er.vectors;
    out.interface_eigenvalues = er.eigenvalues;
  }
  out.summary.modes = nm;

  say(fmt::format("constraint modes: {} solves with the same factorisation", nb));
  const Eigen::MatrixXd psi = constraint_modes(factor, p.k_ib, options.interrupt);
  say("projecting K and M");
  if (options.interrupt) options.interrupt();
  project(p, psi, phi, out.interface_eigenvalues, &out);
  out.summary.report =
      fmt::format("Craig-Bampton: {} DOFs -> {} ({} boundary + {} fixed-interface modes); {}", n,
                  nb + nm, nb, nm, eig_report);
  return out;
}

}  // namespace jointlab::model::fe
