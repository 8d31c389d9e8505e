#include "jointlab/model/iwan.h"

#include <cassert>
#include <cmath>
#include <limits>
#include <utility>

#include <fmt/format.h>

namespace jointlab::model {

std::string ParameterDomain::text() const {
  if (std::isinf(hi)) return fmt::format("{} {}", lo_open ? ">" : ">=", lo);
  return fmt::format("in {}{}, {}{}", lo_open ? "(" : "[", lo, hi, hi_open ? ")" : "]");
}

ParameterDomain iwan_parameter_domain(const std::string& name) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  if (name == "Fs" || name == "Kt") return {0, inf, true, true};
  // Any chi > -1: the density R phi^chi is integrable at 0 and F'(phi_max) = K_T beta / (1 + beta)
  // >= 0 whatever chi (method.md); chi > 0 puts more sliders at large slip displacements.
  if (name == "chi") return {-1, inf, true, true};
  assert(name == "beta");
  return {0, inf, false, true};
}

std::string iwan_parameter_error(const IwanParameters& p) {
  const std::pair<const char*, double> fields[] = {
      {"Fs", p.Fs}, {"Kt", p.Kt}, {"chi", p.chi}, {"beta", p.beta}};
  for (const auto& [name, value] : fields) {
    const ParameterDomain d = iwan_parameter_domain(name);
    if (!d.contains(value)) {
      return fmt::format("{} = {} must be {}{}", name, value,
                         std::isfinite(value) ? "" : "a finite number ", d.text());
    }
  }
  return "";
}

}  // namespace jointlab::model
