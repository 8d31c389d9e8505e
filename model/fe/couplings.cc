#include "jointlab/model/fe/couplings.h"

#include <fmt/format.h>
#include <Eigen/Dense>
#include <Eigen/Geometry>

#include "jointlab/core/error.h"

namespace jointlab::model::fe {

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

Eigen::MatrixXd distributing_coupling_matrix(const Eigen::Vector3d& reference,
                                             const std::vector<Eigen::Vector3d>& patch) {
  const int n = static_cast<int>(patch.size());
  if (n < 3)
    throw InputError(fmt::format(
        "distributing coupling needs at least 3 patch nodes, found {} within the radius", n));
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : patch) centroid += p;
  centroid /= n;
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  double scale = 0;
  for (const auto& p : patch) {
    const Eigen::Vector3d r = p - centroid;
    a += r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose();
    scale += r.squaredNorm();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(a);
  if (eig.eigenvalues().minCoeff() <= 1e-10 * scale)
    throw InputError(fmt::format(
        "distributing coupling patch of {} nodes is collinear: its rotation is undetermined", n));
  const Eigen::Matrix3d a_inv = a.inverse();
  const Eigen::Matrix3d d_skew = skew(reference - centroid);
  Eigen::MatrixXd g(6, 3 * n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Matrix3d rot = a_inv * skew(patch[i] - centroid);  // θ_r contribution
    g.block<3, 3>(3, 3 * i) = rot;
    // u_r = ū + θ_r × d = ū − [d]× θ_r.
    g.block<3, 3>(0, 3 * i) = Eigen::Matrix3d::Identity() / n - d_skew * rot;
  }
  return g;
}

Eigen::Matrix<double, 6, 6> rigid_link_matrix(const Eigen::Vector3d& master,
                                              const Eigen::Vector3d& slave) {
  Eigen::Matrix<double, 6, 6> g = Eigen::Matrix<double, 6, 6>::Identity();
  // u_s = u_m + θ_m × r = u_m − [r]× θ_m.
  g.block<3, 3>(0, 3) = -skew(slave - master);
  return g;
}

}  // namespace jointlab::model::fe
