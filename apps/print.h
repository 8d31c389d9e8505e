// Printing progress, results and errors to the console without ever failing the command.
//
// fmt::print throws std::system_error when its stream cannot be written (a full disk behind
// a redirection, a closed pipe); a progress or error line that cannot be shown must not end
// the command, nor turn its exit status into an abort. Every line the commands print to
// stdout or stderr goes through say().
#pragma once

#include <cstdio>
#include <string>
#include <utility>

#include <fmt/format.h>

namespace jointlab::apps {

/// Formats and writes to `stream`; a failed write (or a failure to format) is ignored.
template <typename... T>
void say(std::FILE* stream, fmt::format_string<T...> format, T&&... args) noexcept {
  try {
    const std::string text = fmt::format(format, std::forward<T>(args)...);
    if (std::fwrite(text.data(), 1, text.size(), stream) != text.size()) std::clearerr(stream);
    if (std::fflush(stream) != 0) std::clearerr(stream);
  } catch (...) {  // NOLINT(bugprone-empty-catch): an unprintable line is dropped
  }
}

}  // namespace jointlab::apps
