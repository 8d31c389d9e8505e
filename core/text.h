// Small text helpers shared by the file readers.
#pragma once

#include <algorithm>
#include <cctype>
#include <cstddef>
#include <string>
#include <string_view>

namespace jointlab {

/// `s` without leading and trailing white space (space, tab, CR, LF, FF, VT).
inline std::string_view trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r\n\f\v");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t\r\n\f\v");
  return s.substr(first, last - first + 1);
}

/// ASCII lower-case copy of `s`.
inline std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

/// `s` for an error message: printable ASCII only ('?' elsewhere), at most 40 characters.
inline std::string printable(std::string_view s) {
  std::string out;
  for (char c : s.substr(0, 40)) {
    const auto u = static_cast<unsigned char>(c);
    out.push_back(u >= 0x20 && u < 0x7f ? c : '?');
  }
  return out;
}

/// `s` cut for a message: at most `max` bytes (never inside a UTF-8 character), then
/// "... (N bytes)" when cut, so a huge name cannot make a huge message.
inline std::string shorten(std::string_view s, size_t max = 80) {
  if (s.size() <= max) return std::string(s);
  size_t n = max;
  while (n > 0 && (static_cast<unsigned char>(s[n]) & 0xC0) == 0x80) --n;
  return std::string(s.substr(0, n)) + "... (" + std::to_string(s.size()) + " bytes)";
}

/// `n` and `noun` for a message, the noun plural unless n is 1: counted(1, "elastic mode") is
/// "1 elastic mode", counted(3, "elastic mode") "3 elastic modes".
inline std::string counted(long long n, std::string_view noun) {
  return std::to_string(n) + " " + std::string(noun) + (n == 1 ? "" : "s");
}

}  // namespace jointlab
