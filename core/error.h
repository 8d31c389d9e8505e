// Error types shared by every jointlab library.
//
// Three channels, never mixed: bad user input throws InputError (message names
// the file, line or field); numerical outcomes are statuses in a Summary;
// programmer errors are asserts.
#pragma once

#include <stdexcept>
#include <string>

namespace jointlab {

/// Bad user input: an unreadable, inconsistent or unphysical file, field or argument.
class InputError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// Builds "file:line: message" (line omitted when 0) for InputError messages.
std::string where(const std::string& file, long line, const std::string& message);

}  // namespace jointlab
