// The 4-parameter Iwan element (Segalman 2005): closed-form virgin curve, tangent,
// stored energy and dissipation per Masing cycle.
//
// Parameters: slip force F_S [N], stiffness at zero load K_T [N/m], power-law exponent
// chi (-1 < chi), macroslip weight beta >= 0. With c = (chi+1)/(chi+2):
//   phi_max = F_S (1+beta) / (K_T (beta + c))                    [m]
//   R       = F_S (chi+1) / (phi_max^(chi+2) (beta + c))
//   S       = (F_S / phi_max) beta / (beta + c)                  [N/m]
// The element is a continuum of unit-stiffness Jenkins sliders with slip-displacement
// density R phi^chi on (0, phi_max) plus S delta(phi - phi_max); K_T = R phi_max^(chi+1)/(chi+1) +
// S. Virgin force, odd in u, for 0 <= u < phi_max:
//   F(u)  = K_T u - R u^(chi+2) / ((chi+1)(chi+2)),   F(u) = F_S for u >= phi_max,
//   F'(u) = K_T - R u^(chi+1) / (chi+1)               (0 past phi_max).
// Dissipation of one symmetric cycle of amplitude A (Masing: 8 int_0^A F - 4 A F(A)):
//   D(A) = 4 R A^(chi+3) / ((chi+2)(chi+3))                    for A < phi_max,
//   D(A) = 8 (E_max + F_S (A - phi_max)) - 4 A F_S              for A >= phi_max,
// with E_max = E(phi_max) and E(u) = int_0^u F = K_T u^2/2 - R u^(chi+3)/((chi+1)(chi+2)(chi+3)).
// QSMA uses the softening h(u) = K_T u - F(u) (the force the element no longer carries
// relative to its linear stiffness), its derivative and its integral.
//
// Everything is templated on the scalar T so that ceres::Jet gives exact derivatives
// with respect to the displacement and to the four parameters.
#pragma once

#include <cmath>
#include <string>

namespace jointlab::model {

/// The four Iwan parameters as read from a model file (SI units).
struct IwanParameters {
  double Fs = 0;    ///< slip force [N]
  double Kt = 0;    ///< stiffness at zero load [N/m]
  double chi = 0;   ///< power-law exponent, > -1
  double beta = 0;  ///< weight of the macroslip delta, >= 0
};

/// The physical domain of one Iwan parameter: an interval with open or closed ends.
struct ParameterDomain {
  double lo = 0;         ///< lower end
  double hi = 0;         ///< upper end (infinity: unbounded above, values must still be finite)
  bool lo_open = false;  ///< lo itself excluded
  bool hi_open = false;  ///< hi itself excluded
  /// True when x is finite and inside.
  bool contains(double x) const {
    return std::isfinite(x) && (lo_open ? x > lo : x >= lo) && (hi_open ? x < hi : x <= hi);
  }
  /// The domain as a phrase: "> 0", ">= 0", "> -1", "in (-1, 0]".
  std::string text() const;
};

/// The domain of the Iwan parameter `name` ("Fs", "Kt", "chi" or "beta"): Fs > 0, Kt > 0,
/// chi > -1, beta >= 0, each finite (method.md); the one place every reader and updater checks.
ParameterDomain iwan_parameter_domain(const std::string& name);

/// What is unphysical about a parameter set ("chi = -1 must be > -1"), or "" if valid;
/// the message starts with the field's name.
std::string iwan_parameter_error(const IwanParameters& p);

/// A 4-parameter Iwan element with scalar type T (double or ceres::Jet).
template <typename T>
class BasicIwan {
 public:
  /// Builds the element; the parameters must satisfy iwan_parameter_error() == "".
  BasicIwan(const T& Fs, const T& Kt, const T& chi, const T& beta)
      : Fs_(Fs), Kt_(Kt), chi_(chi), beta_(beta) {
    using std::pow;
    const T c = (chi + T(1)) / (chi + T(2));
    phi_max_ = Fs * (T(1) + beta) / (Kt * (beta + c));
    R_ = Fs * (chi + T(1)) / (pow(phi_max_, chi + T(2)) * (beta + c));
    S_ = Fs / phi_max_ * beta / (beta + c);
  }
  /// Builds a double-valued element from a parameter set.
  explicit BasicIwan(const IwanParameters& p) : BasicIwan(T(p.Fs), T(p.Kt), T(p.chi), T(p.beta)) {}

  /// Slip force F_S [N].
  const T& slip_force() const { return Fs_; }
  /// Stiffness at zero load K_T [N/m].
  const T& stiffness() const { return Kt_; }
  /// Power-law exponent chi.
  const T& chi() const { return chi_; }
  /// Macroslip weight beta.
  const T& beta() const { return beta_; }
  /// Displacement at which every slider slips (macroslip) [m].
  const T& phi_max() const { return phi_max_; }
  /// Coefficient R of the slider density R phi^chi.
  const T& R() const { return R_; }
  /// Weight S of the slider delta at phi_max [N/m].
  const T& S() const { return S_; }

  /// Virgin (monotonic) force F(u) [N], odd in u.
  T force(const T& u) const {
    if (u < T(0)) return -force(-u);
    if (u >= phi_max_) return Fs_;
    return Kt_ * u - R_ * power(u, chi_ + T(2)) / ((chi_ + T(1)) * (chi_ + T(2)));
  }

  /// Virgin tangent stiffness F'(u) [N/m], even in u; 0 in macroslip.
  T tangent(const T& u) const {
    if (u < T(0)) return tangent(-u);
    if (u >= phi_max_) return T(0);
    return Kt_ - R_ * power(u, chi_ + T(1)) / (chi_ + T(1));
  }

  /// Energy stored along the virgin curve, E(u) = int_0^|u| F [J], even in u.
  T energy(const T& u) const {
    if (u < T(0)) return energy(-u);
    if (u >= phi_max_) return energy_below(phi_max_) + Fs_ * (u - phi_max_);
    return energy_below(u);
  }

  /// Energy dissipated in one symmetric Masing cycle of amplitude |A| [J].
  T dissipation(const T& A) const {
    if (A < T(0)) return dissipation(-A);
    if (A >= phi_max_) {
      return T(8) * (energy_below(phi_max_) + Fs_ * (A - phi_max_)) - T(4) * A * Fs_;
    }
    return T(4) * R_ * power(A, chi_ + T(3)) / ((chi_ + T(2)) * (chi_ + T(3)));
  }

  /// Softening h(u) = K_T u - F(u) [N], odd in u.
  T softening(const T& u) const { return Kt_ * u - force(u); }
  /// Derivative of the softening, h'(u) = K_T - F'(u) in [0, K_T].
  T softening_tangent(const T& u) const { return Kt_ - tangent(u); }
  /// Integral of the softening, K_T u^2/2 - E(u) [J], even in u.
  T softening_energy(const T& u) const { return Kt_ * u * u / T(2) - energy(u); }

 private:
  // u^e for u >= 0, with 0^e = 0 (e > 0): avoids log(0) in the Jet derivative.
  static T power(const T& u, const T& e) {
    using std::pow;
    if (u <= T(0)) return T(0);
    return pow(u, e);
  }
  T energy_below(const T& u) const {
    return Kt_ * u * u / T(2) -
           R_ * power(u, chi_ + T(3)) / ((chi_ + T(1)) * (chi_ + T(2)) * (chi_ + T(3)));
  }

  T Fs_, Kt_, chi_, beta_;
  T phi_max_, R_, S_;
};

/// The double-valued Iwan element used by models and QSMA.
using Iwan = BasicIwan<double>;

}  // namespace jointlab::model
