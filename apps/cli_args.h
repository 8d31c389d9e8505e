// Checks of command-line arguments that more than one command makes.
#pragma once

#include <string>

#include "jointlab/core/units.h"

namespace jointlab::apps {

/// The motion quantity `value` names (displacement, velocity or acceleration); InputError
/// naming `option` for anything else, force included.
Quantity motion_quantity(const std::string& option, const std::string& value);

}  // namespace jointlab::apps
