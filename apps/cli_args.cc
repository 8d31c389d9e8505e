#include "jointlab/apps/cli_args.h"

#include <fmt/format.h>

#include "jointlab/core/error.h"

namespace jointlab::apps {

Quantity motion_quantity(const std::string& option, const std::string& value) {
  const auto q = parse_quantity(value);
  if (!q || *q == Quantity::kForce) {
    throw InputError(
        fmt::format("{} {}: expected displacement, velocity or acceleration", option, value));
  }
  return *q;
}

}  // namespace jointlab::apps
