// Checks of command-line arguments that more than one command makes.
#pragma once

#include <string>
#include <vector>

#include "jointlab/core/units.h"

namespace jointlab::apps {

/// The motion quantity `value` names (displacement, velocity or acceleration); InputError
/// naming `option` for anything else, force included.
Quantity motion_quantity(const std::string& option, const std::string& value);

/// InputError when two input files share a stem: their outputs, named after it, would collide.
void check_distinct_stems(const std::vector<std::string>& files);

}  // namespace jointlab::apps
