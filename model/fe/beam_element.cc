#include "jointlab/model/fe/beam_element.h"

#include <cassert>
#include <cmath>

#include <Eigen/Geometry>

namespace jointlab::model::fe {
namespace {

using Matrix4 = Eigen::Matrix4d;

// Bending stiffness of the (v, θz) plane, θz = dv/dx convention.
Matrix4 bending_stiffness(double ei, double length, double phi) {
  const double l = length;
  Matrix4 k;
  k << 12, 6 * l, -12, 6 * l,                               //
      6 * l, (4 + phi) * l * l, -6 * l, (2 - phi) * l * l,  //
      -12, -6 * l, 12, -6 * l,                              //
      6 * l, (2 - phi) * l * l, -6 * l, (4 + phi) * l * l;
  return k * ei / ((1 + phi) * l * l * l);
}

// Consistent mass of the (v, θz) plane: translational plus rotary inertia.
Matrix4 bending_mass(double rho_a, double rho_i, double length, double phi) {
  const double l = length, p = phi, p2 = phi * phi;
  const double m11 = 13.0 / 35 + 7.0 / 10 * p + p2 / 3;
  const double m12 = (11.0 / 210 + 11.0 / 120 * p + p2 / 24) * l;
  const double m13 = 9.0 / 70 + 3.0 / 10 * p + p2 / 6;
  const double m14 = -(13.0 / 420 + 3.0 / 40 * p + p2 / 24) * l;
  const double m22 = (1.0 / 105 + p / 60 + p2 / 120) * l * l;
  const double m24 = -(1.0 / 140 + p / 60 + p2 / 120) * l * l;
  Matrix4 mt;
  mt << m11, m12, m13, m14,  //
      m12, m22, -m14, m24,   //
      m13, -m14, m11, -m12,  //
      m14, m24, -m12, m22;
  const double r11 = 6.0 / 5;
  const double r12 = (1.0 / 10 - p / 2) * l;
  const double r22 = (2.0 / 15 + p / 6 + p2 / 3) * l * l;
  const double r24 = (-1.0 / 30 - p / 6 + p2 / 6) * l * l;
  Matrix4 mr;
  mr << r11, r12, -r11, r12,  //
      r12, r22, -r12, r24,    //
      -r11, -r12, r11, -r12,  //
      r12, r24, -r12, r22;
  const double s = (1 + p) * (1 + p);
  return mt * (rho_a * l / s) + mr * (rho_i / (l * s));
}

// Scatters a 4×4 plane matrix into the 12×12 local matrix at DOFs idx.
void scatter(Eigen::Matrix<double, 12, 12>& into, const Matrix4& m, const int (&idx)[4]) {
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) into(idx[i], idx[j]) += m(i, j);
}

void scatter2(Eigen::Matrix<double, 12, 12>& into, double diag, double off, int i, int j) {
  into(i, i) += diag;
  into(j, j) += diag;
  into(i, j) += off;
  into(j, i) += off;
}

}  // namespace

BeamSection rectangular_section(double youngs_modulus, double poissons_ratio, double density,
                                double width, double height) {
  BeamSection s;
  s.youngs_modulus = youngs_modulus;
  s.shear_modulus = youngs_modulus / (2 * (1 + poissons_ratio));
  s.density = density;
  s.area = width * height;
  s.inertia_y = width * height * height * height / 12;
  s.inertia_z = height * width * width * width / 12;
  const double a = std::max(width, height), b = std::min(width, height);
  // Thin-rectangle series (Roark), within 4 % for every aspect ratio.
  s.torsion_constant = a * b * b * b * (1.0 / 3 - 0.21 * b / a * (1 - std::pow(b / a, 4) / 12));
  return s;
}

ElementMatrices beam_element(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                             const Eigen::Vector3d& y_axis, const BeamSection& s) {
  const Eigen::Vector3d axis = b - a;
  const double l = axis.norm();
  assert(l > 0);
  const Eigen::Vector3d e1 = axis / l;
  Eigen::Vector3d e2 = y_axis - y_axis.dot(e1) * e1;
  assert(e2.norm() > 1e-8 * y_axis.norm());
  e2.normalize();
  const Eigen::Vector3d e3 = e1.cross(e2);

  const double e = s.youngs_modulus, g = s.shear_modulus, k = s.shear_coefficient;
  const double phi_z = 12 * e * s.inertia_z / (k * g * s.area * l * l);  // v–θz plane
  const double phi_y = 12 * e * s.inertia_y / (k * g * s.area * l * l);  // w–θy plane

  Eigen::Matrix<double, 12, 12> kl = Eigen::Matrix<double, 12, 12>::Zero();
  Eigen::Matrix<double, 12, 12> ml = Eigen::Matrix<double, 12, 12>::Zero();
  // Axial and torsion.
  scatter2(kl, e * s.area / l, -e * s.area / l, 0, 6);
  scatter2(kl, g * s.torsion_constant / l, -g * s.torsion_constant / l, 3, 9);
  const double m_ax = s.density * s.area * l / 6;
  scatter2(ml, 2 * m_ax, m_ax, 0, 6);
  const double m_tor = s.density * (s.inertia_y + s.inertia_z) * l / 6;
  scatter2(ml, 2 * m_tor, m_tor, 3, 9);
  // x–y plane: (v1, θz1, v2, θz2), θz = dv/dx.
  const int xy[4] = {1, 5, 7, 11};
  scatter(kl, bending_stiffness(e * s.inertia_z, l, phi_z), xy);
  scatter(ml, bending_mass(s.density * s.area, s.density * s.inertia_z, l, phi_z), xy);
  // x–z plane: (w1, θy1, w2, θy2), θy = −dw/dx: the same matrices with the rotations negated.
  const Matrix4 flip = Eigen::Vector4d(1, -1, 1, -1).asDiagonal();
  const int xz[4] = {2, 4, 8, 10};
  scatter(kl, flip * bending_stiffness(e * s.inertia_y, l, phi_y) * flip, xz);
  scatter(ml, flip * bending_mass(s.density * s.area, s.density * s.inertia_y, l, phi_y) * flip,
          xz);

  // u_local = R u_global per 3-vector.
  return to_global<12>(kl, ml, e1, e2, e3);
}

}  // namespace jointlab::model::fe
