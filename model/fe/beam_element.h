// Two-node 3D shear-deformable (Timoshenko) beam element, 6 DOFs per node.
//
// Local frame: e1 along the axis (node a -> b), e2 the component of the user's `y_axis`
// normal to e1, e3 = e1 × e2. Local DOFs per node (u, v, w, θx, θy, θz); the section's
// I_y bends in the x–z plane (w, θy = −dw/dx for a slender beam), I_z in the x–y plane
// (v, θz = dv/dx). Stiffness is exact for the Timoshenko beam (Przemieniecki): with
// Φ = 12 E I / (κ G A L²),
//   k_bend = E I / ((1+Φ) L³) [12, 6L, −12, 6L; ·, (4+Φ)L², −6L, (2−Φ)L²; ...],
// axial EA/L, torsion GJ/L. The consistent mass is the one of the same interpolation
// (Friedman–Kosmatka): translational ρA L terms and rotary ρI terms, each a quadratic in
// Φ over (1+Φ)²; axial ρAL/6 [2 1; 1 2], torsion ρ(I_y+I_z)L/6 [2 1; 1 2]. At Φ = 0 both
// reduce to the Euler–Bernoulli matrices. SI units throughout.
#pragma once

#include <Eigen/Core>

#include "jointlab/model/fe/element_matrices.h"

namespace jointlab::model::fe {

/// Material and cross-section of a beam (SI: Pa, kg/m³, m², m⁴).
struct BeamSection {
  double youngs_modulus = 0;    ///< E [Pa].
  double shear_modulus = 0;     ///< G [Pa].
  double density = 0;           ///< ρ [kg/m³].
  double area = 0;              ///< A [m²].
  double inertia_y = 0;         ///< I_y, second moment about local y (bending in x–z) [m⁴].
  double inertia_z = 0;         ///< I_z, second moment about local z (bending in x–y) [m⁴].
  double torsion_constant = 0;  ///< J, St Venant torsion constant [m⁴].
  double shear_coefficient = 5.0 / 6.0;  ///< κ, the same for both bending planes.
};

/// The section of a solid b × h rectangle (b along local y, h along local z).
BeamSection rectangular_section(double youngs_modulus, double poissons_ratio, double density,
                                double width, double height);

/// Global 12×12 stiffness and consistent mass of a Timoshenko beam from `a` to `b`;
/// `y_axis` fixes the local y direction (must not be parallel to the axis).
ElementMatrices beam_element(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                             const Eigen::Vector3d& y_axis, const BeamSection& section);

}  // namespace jointlab::model::fe
