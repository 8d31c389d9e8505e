// A small, strict JSON reader for the files jointlab writes (summary.json of `process`).
//
// Hand-written because the fixed Debian build stack has no JSON library (json_writer.h is
// hand-written for the same reason) and jointlab reads only its own, simple documents.
// Accepted: RFC 8259 JSON — objects, arrays, strings (with the standard escapes, \uXXXX
// including surrogate pairs, encoded as UTF-8), numbers (the JSON grammar only: no leading
// '+', no leading zeros, no NaN or Infinity), true, false, null; whitespace between tokens.
// Refused with a one-line InputError "file:line: column C (byte B): what": anything else,
// trailing text after the document, duplicate keys in one object, nesting deeper than 256.
// Object keys keep their order of appearance.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace jointlab::data {

/// One JSON value: null, boolean, number, string, array or object.
class JsonValue {
 public:
  /// The kind of a value.
  enum class Type { kNull, kBool, kNumber, kString, kArray, kObject };

  /// Type of this value.
  Type type() const { return type_; }
  /// True for null.
  bool is_null() const { return type_ == Type::kNull; }
  /// True for a number.
  bool is_number() const { return type_ == Type::kNumber; }
  /// True for a string.
  bool is_string() const { return type_ == Type::kString; }
  /// True for an array.
  bool is_array() const { return type_ == Type::kArray; }
  /// True for an object.
  bool is_object() const { return type_ == Type::kObject; }
  /// The boolean (false unless a boolean).
  bool boolean() const { return boolean_; }
  /// The number (0 unless a number).
  double number() const { return number_; }
  /// The string ("" unless a string).
  const std::string& string() const { return string_; }
  /// Elements of an array (empty otherwise).
  const std::vector<JsonValue>& items() const { return items_; }
  /// Members of an object in file order (empty otherwise).
  const std::vector<std::pair<std::string, JsonValue>>& members() const { return members_; }
  /// The member named `key` of an object, or nullptr (also for a non-object).
  const JsonValue* find(std::string_view key) const;
  /// Name of a type for messages ("number", "object", ...).
  static const char* type_name(Type t);

 private:
  friend class JsonParser;
  Type type_ = Type::kNull;
  bool boolean_ = false;
  double number_ = 0;
  std::string string_;
  std::vector<JsonValue> items_;
  std::vector<std::pair<std::string, JsonValue>> members_;
};

/// Parses JSON text as if read from a file named `name`; InputError naming name, line, column
/// and byte offset on any defect.
JsonValue parse_json(std::string_view text, const std::string& name);

/// Reads and parses a JSON file; InputError if it cannot be read or is not valid JSON.
JsonValue read_json(const std::filesystem::path& path);

}  // namespace jointlab::data
