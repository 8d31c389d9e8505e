#include "jointlab/model/iwan.h"

#include <cmath>

#include <fmt/format.h>

namespace jointlab::model {

std::string iwan_parameter_error(const IwanParameters& p) {
  if (!std::isfinite(p.Fs) || p.Fs <= 0) return fmt::format("Fs = {} must be > 0", p.Fs);
  if (!std::isfinite(p.Kt) || p.Kt <= 0) return fmt::format("Kt = {} must be > 0", p.Kt);
  if (!std::isfinite(p.chi) || p.chi <= -1) return fmt::format("chi = {} must be > -1", p.chi);
  if (!std::isfinite(p.beta) || p.beta < 0) return fmt::format("beta = {} must be >= 0", p.beta);
  return "";
}

}  // namespace jointlab::model
