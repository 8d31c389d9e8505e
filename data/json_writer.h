// A small streaming JSON writer for summary files.
//
// Written here rather than taken from a library because the fixed Debian stack
// has no JSON library and jointlab only ever writes JSON (never parses it).
// Strings are escaped, and bytes that are not valid UTF-8 become U+FFFD (input files may
// name channels in any encoding; JSON must be UTF-8). Numbers print with 12 significant
// digits; a non-finite number throws
// std::logic_error (results never contain NaN).
#pragma once

#include <initializer_list>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace jointlab::data {

/// Builds a JSON document by nested begin/end calls; commas and indentation are handled.
class JsonWriter {
 public:
  /// Starts an object (as a value, or after key()).
  JsonWriter& begin_object();
  /// Ends the innermost object.
  JsonWriter& end_object();
  /// Starts an array.
  JsonWriter& begin_array();
  /// Ends the innermost array.
  JsonWriter& end_array();
  /// Writes an object key; the next call writes its value.
  JsonWriter& key(std::string_view k);
  /// Writes a string value (escaped).
  JsonWriter& value(std::string_view s);
  /// Writes a string value (escaped).
  JsonWriter& value(const char* s) { return value(std::string_view(s)); }
  /// Writes a number; throws std::logic_error if not finite.
  JsonWriter& value(double x);
  /// Writes an integer.
  JsonWriter& value(long x);
  /// Writes an integer.
  JsonWriter& value(int x) { return value(static_cast<long>(x)); }
  /// Writes a boolean.
  JsonWriter& value(bool b);
  /// Writes null.
  JsonWriter& null();
  /// Writes one key and number per entry, in the order given (each as value(double)).
  JsonWriter& numbers(std::initializer_list<std::pair<std::string_view, double>> entries);
  /// The document so far (complete once every begin has its end).
  const std::string& str() const { return out_; }

 private:
  void before_value();
  void write_string(std::string_view s);
  void newline();
  std::string out_;
  std::vector<bool> first_;  // per open container: no element written yet
  bool after_key_ = false;
};

}  // namespace jointlab::data
