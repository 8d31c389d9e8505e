// Four-node flat shell element: MITC4 plate bending + incompatible-mode membrane + drilling.
//
// Local frame: e1 along the element's ξ direction (x1+x2−x0−x3), e3 the normal
// (g_ξ × g_η), e2 = e3 × e1; nodes counter-clockwise about e3. Through the thickness
// u(z) = u0 + z θy, v(z) = v0 − z θx (θ right-handed about the local axes), so
//   curvatures  κ = (θy,x, −θx,y, θy,y − θx,x),  D_b = E t³/(12(1−ν²)) [1 ν 0; ν 1 0; 0 0 (1−ν)/2]
//   shear       γ = (w,x + θy, w,y − θx),         D_s = κ G t, κ = 5/6
//   membrane    ε = (u,x, v,y, u,y + v,x),         D_m = E t/(1−ν²) [1 ν 0; ν 1 0; 0 0 (1−ν)/2].
// Transverse shear follows MITC4 (Bathe–Dvorkin): the covariant strains γ_ξ, γ_η are tied
// at the edge midpoints and interpolated, so thin plates do not lock and no spurious
// modes appear (2×2 Gauss). The membrane adds the four incompatible modes (1−ξ²), (1−η²)
// per direction (Wilson–Taylor QM6, derivatives at the centre Jacobian so the patch test
// passes), condensed out; in-plane bending is then exact on rectangles. Drilling rotations
// θz get the Hughes–Brezzi penalty γ_d ∫ (θz − ½(v,x − u,y))² dA with γ_d = α G t (α =
// `drilling_factor`, small), which is zero for rigid motion. Mass is consistent: ρt N·N for
// the translations, ρt³/12 N·N for θx, θy and a small fraction of that for θz (drilling
// modes, an artefact of the formulation, then sit far above the membrane spectrum instead
// of crowding a Craig–Bampton fixed-interface basis). SI units.
#pragma once

#include <array>

#include <Eigen/Core>

#include "jointlab/model/fe/element_matrices.h"

namespace jointlab::model::fe {

/// Material and thickness of a homogeneous shell (SI: Pa, kg/m³, m).
struct ShellSection {
  double youngs_modulus = 0;      ///< E [Pa].
  double poissons_ratio = 0;      ///< ν.
  double density = 0;             ///< ρ [kg/m³].
  double thickness = 0;           ///< t [m].
  double drilling_factor = 1e-3;  ///< α of the drilling penalty γ_d = α G t.
  /// Drilling rotary inertia as a fraction of ρt³/12 (it has no physical counterpart; small
  /// keeps the artificial drilling modes far above the physical spectrum).
  double drilling_inertia_factor = 1e-4;
};

/// Global 24×24 stiffness and consistent mass of a flat MITC4 shell on four corner nodes
/// (counter-clockwise; the element must be flat to within round-off).
ElementMatrices shell_element(const std::array<Eigen::Vector3d, 4>& nodes,
                              const ShellSection& section);

}  // namespace jointlab::model::fe
