// Reading MATLAB variables as matio gives them: element counts and char arrays.
#pragma once

#include <cstddef>
#include <optional>
#include <string>

#include <matio.h>

namespace jointlab::data {

/// Number of elements of `v`, or nullopt when it is null, its dimensions are malformed or
/// their product overflows.
std::optional<std::size_t> mat_element_count(const matvar_t* v);

/// A char array as text, rows joined by newlines, characters outside printable ASCII as '?';
/// nullopt when `v` is not a well-formed char array.
std::optional<std::string> mat_char_text(const matvar_t* v);

}  // namespace jointlab::data
