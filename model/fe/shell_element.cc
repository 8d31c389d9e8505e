#include "jointlab/model/fe/shell_element.h"

#include <cassert>
#include <cmath>

#include <Eigen/Dense>
#include <Eigen/Geometry>

namespace jointlab::model::fe {
namespace {

constexpr double kXi[4] = {-1, 1, 1, -1};
constexpr double kEta[4] = {-1, -1, 1, 1};

struct Shape {
  Eigen::Vector4d n;     // N_i
  Eigen::Vector4d dxi;   // ∂N_i/∂ξ
  Eigen::Vector4d deta;  // ∂N_i/∂η
};

Shape shape(double xi, double eta) {
  Shape s;
  for (int i = 0; i < 4; ++i) {
    s.n(i) = 0.25 * (1 + xi * kXi[i]) * (1 + eta * kEta[i]);
    s.dxi(i) = 0.25 * kXi[i] * (1 + eta * kEta[i]);
    s.deta(i) = 0.25 * kEta[i] * (1 + xi * kXi[i]);
  }
  return s;
}

// J = [x_ξ y_ξ; x_η y_η].
Eigen::Matrix2d jacobian(const Shape& s, const Eigen::Vector4d& x, const Eigen::Vector4d& y) {
  Eigen::Matrix2d j;
  j << s.dxi.dot(x), s.dxi.dot(y), s.deta.dot(x), s.deta.dot(y);
  return j;
}

// Local DOF index of component c (0..5 = u v w θx θy θz) at node i.
constexpr int dof(int i, int c) { return 6 * i + c; }

// Covariant transverse shear row at (ξ, η): γ_ξ (which = 0) or γ_η (which = 1),
// γ_ξ = w,ξ + x_ξ θy − y_ξ θx.
Eigen::Matrix<double, 1, 24> covariant_shear(double xi, double eta, int which,
                                             const Eigen::Vector4d& x, const Eigen::Vector4d& y) {
  const Shape s = shape(xi, eta);
  const Eigen::Vector4d& d = which == 0 ? s.dxi : s.deta;
  const double xd = d.dot(x), yd = d.dot(y);
  Eigen::Matrix<double, 1, 24> b = Eigen::Matrix<double, 1, 24>::Zero();
  for (int i = 0; i < 4; ++i) {
    b(dof(i, 2)) = d(i);
    b(dof(i, 4)) = xd * s.n(i);
    b(dof(i, 3)) = -yd * s.n(i);
  }
  return b;
}

}  // namespace

ElementMatrices shell_element(const std::array<Eigen::Vector3d, 4>& p, const ShellSection& sec) {
  // Local frame.
  const Eigen::Vector3d g1 = 0.5 * (p[1] + p[2] - p[0] - p[3]);
  const Eigen::Vector3d g2 = 0.5 * (p[2] + p[3] - p[0] - p[1]);
  const Eigen::Vector3d e3 = g1.cross(g2).normalized();
  const Eigen::Vector3d e1 = g1.normalized();
  const Eigen::Vector3d e2 = e3.cross(e1);
  const Eigen::Vector3d c = 0.25 * (p[0] + p[1] + p[2] + p[3]);
  Eigen::Vector4d x, y;
  for (int i = 0; i < 4; ++i) {
    x(i) = (p[i] - c).dot(e1);
    y(i) = (p[i] - c).dot(e2);
    assert(std::abs((p[i] - c).dot(e3)) <= 1e-8 * g1.norm());
  }

  const double e = sec.youngs_modulus, nu = sec.poissons_ratio, t = sec.thickness;
  const double g = e / (2 * (1 + nu));
  Eigen::Matrix3d iso;
  iso << 1, nu, 0, nu, 1, 0, 0, 0, (1 - nu) / 2;
  iso /= (1 - nu * nu);
  const Eigen::Matrix3d dm = e * t * iso;
  const Eigen::Matrix3d db = e * t * t * t / 12 * iso;
  const double ds = 5.0 / 6.0 * g * t;
  const double gamma_drill = sec.drilling_factor * g * t;

  // MITC4 tying points: γ_ξ at A (0,−1), C (0,1); γ_η at B (−1,0), D (1,0).
  const Eigen::Matrix<double, 1, 24> ga = covariant_shear(0, -1, 0, x, y);
  const Eigen::Matrix<double, 1, 24> gc = covariant_shear(0, 1, 0, x, y);
  const Eigen::Matrix<double, 1, 24> gb = covariant_shear(-1, 0, 1, x, y);
  const Eigen::Matrix<double, 1, 24> gd = covariant_shear(1, 0, 1, x, y);

  const Shape s0 = shape(0, 0);
  const Eigen::Matrix2d j0 = jacobian(s0, x, y);
  const double det0 = j0.determinant();
  const Eigen::Matrix2d j0inv = j0.inverse();

  Eigen::Matrix<double, 24, 24> k = Eigen::Matrix<double, 24, 24>::Zero();
  Eigen::Matrix<double, 24, 24> m = Eigen::Matrix<double, 24, 24>::Zero();
  Eigen::Matrix<double, 24, 4> k_ci =
      Eigen::Matrix<double, 24, 4>::Zero();  // compatible–incompatible
  Eigen::Matrix4d k_ii = Eigen::Matrix4d::Zero();

  const double gp = 1 / std::sqrt(3.0);
  for (int q = 0; q < 4; ++q) {
    const double xi = kXi[q] * gp, eta = kEta[q] * gp;
    const Shape s = shape(xi, eta);
    const Eigen::Matrix2d j = jacobian(s, x, y);
    const double det = j.determinant();
    assert(det > 0);
    const Eigen::Matrix2d jinv = j.inverse();
    // Cartesian derivatives: [N,x; N,y] = J⁻¹ [N,ξ; N,η].
    Eigen::Matrix<double, 2, 4> dn;
    dn.row(0) = s.dxi.transpose();
    dn.row(1) = s.deta.transpose();
    const Eigen::Matrix<double, 2, 4> dxy = jinv * dn;

    Eigen::Matrix<double, 3, 24> bm = Eigen::Matrix<double, 3, 24>::Zero();
    Eigen::Matrix<double, 3, 24> bb = Eigen::Matrix<double, 3, 24>::Zero();
    Eigen::Matrix<double, 1, 24> bd = Eigen::Matrix<double, 1, 24>::Zero();
    for (int i = 0; i < 4; ++i) {
      const double nx = dxy(0, i), ny = dxy(1, i);
      bm(0, dof(i, 0)) = nx;
      bm(1, dof(i, 1)) = ny;
      bm(2, dof(i, 0)) = ny;
      bm(2, dof(i, 1)) = nx;
      bb(0, dof(i, 4)) = nx;
      bb(1, dof(i, 3)) = -ny;
      bb(2, dof(i, 4)) = ny;
      bb(2, dof(i, 3)) = -nx;
      bd(dof(i, 5)) = s.n(i);
      bd(dof(i, 1)) = -0.5 * nx;
      bd(dof(i, 0)) = 0.5 * ny;
    }
    // Assumed covariant shear, then Cartesian: γ = J⁻¹ [γ_ξ; γ_η].
    Eigen::Matrix<double, 2, 24> gcov;
    gcov.row(0) = 0.5 * (1 - eta) * ga + 0.5 * (1 + eta) * gc;
    gcov.row(1) = 0.5 * (1 - xi) * gb + 0.5 * (1 + xi) * gd;
    const Eigen::Matrix<double, 2, 24> bs = jinv * gcov;

    // Incompatible membrane modes u = a1(1−ξ²) + a2(1−η²), v = a3(1−ξ²) + a4(1−η²),
    // derivatives through J0 and scaled by det J0 / det J (Taylor).
    const Eigen::Vector2d dp = j0inv * Eigen::Vector2d(-2 * xi, 0) * (det0 / det);
    const Eigen::Vector2d dq = j0inv * Eigen::Vector2d(0, -2 * eta) * (det0 / det);
    Eigen::Matrix<double, 3, 4> bi;
    bi << dp(0), dq(0), 0, 0,  //
        0, 0, dp(1), dq(1),    //
        dp(1), dq(1), dp(0), dq(0);

    const double w = det;  // Gauss weights are 1.
    k += w * (bm.transpose() * dm * bm + bb.transpose() * db * bb + ds * bs.transpose() * bs +
              gamma_drill * bd.transpose() * bd);
    k_ci += w * bm.transpose() * dm * bi;
    k_ii += w * bi.transpose() * dm * bi;

    const Eigen::Matrix4d nn = s.n * s.n.transpose() * w;
    const double mt = sec.density * t, mr = sec.density * t * t * t / 12;
    const double md = sec.drilling_inertia_factor * mr;
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        for (int cc = 0; cc < 6; ++cc)
          m(dof(a, cc), dof(b, cc)) += (cc < 3 ? mt : cc < 5 ? mr : md) * nn(a, b);
  }
  k -= k_ci * k_ii.ldlt().solve(k_ci.transpose());
  k = 0.5 * (k + k.transpose()).eval();

  return to_global<24>(k, m, e1, e2, e3);
}

}  // namespace jointlab::model::fe
