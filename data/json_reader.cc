#include "jointlab/data/json_reader.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/data/csv_lines.h"

namespace jointlab::data {

const JsonValue* JsonValue::find(std::string_view key) const {
  for (const auto& [k, v] : members_) {
    if (k == key) return &v;
  }
  return nullptr;
}

const char* JsonValue::type_name(Type t) {
  switch (t) {
    case Type::kNull:
      return "null";
    case Type::kBool:
      return "boolean";
    case Type::kNumber:
      return "number";
    case Type::kString:
      return "string";
    case Type::kArray:
      return "array";
    case Type::kObject:
      return "object";
  }
  return "value";
}

// Recursive descent over the text; pos_ is the byte offset of the next character.
class JsonParser {
 public:
  JsonParser(std::string_view text, const std::string& name) : text_(text), name_(name) {}

  JsonValue document() {
    skip_space();
    JsonValue v = value(0);
    skip_space();
    if (pos_ < text_.size()) fail("unexpected text after the JSON document");
    return v;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    long line = 1;
    size_t line_start = 0;
    for (size_t i = 0; i < pos_ && i < text_.size(); ++i) {
      if (text_[i] == '\n') {
        ++line;
        line_start = i + 1;
      }
    }
    throw InputError(where(
        name_, line, fmt::format("column {} (byte {}): {}", pos_ - line_start + 1, pos_, what)));
  }

  bool at_end() const { return pos_ >= text_.size(); }
  char peek() const { return at_end() ? '\0' : text_[pos_]; }

  void skip_space() {
    while (!at_end() && (peek() == ' ' || peek() == '\t' || peek() == '\n' || peek() == '\r')) {
      ++pos_;
    }
  }

  void expect(char c, const char* what) {
    if (peek() != c)
      fail(at_end() ? fmt::format("end of file where {} was expected", what)
                    : fmt::format("'{}' where {} was expected", peek(), what));
    ++pos_;
  }

  JsonValue value(int depth) {
    if (depth > 256) fail("nesting deeper than 256 levels");
    JsonValue v;
    if (at_end()) fail("end of file where a value was expected");
    const char c = peek();
    if (c == '{') {
      v.type_ = JsonValue::Type::kObject;
      ++pos_;
      skip_space();
      if (peek() == '}') {
        ++pos_;
        return v;
      }
      for (;;) {
        skip_space();
        if (peek() != '"') fail("an object key must be a string");
        const size_t key_pos = pos_;
        std::string key = string();
        if (v.find(key)) {
          pos_ = key_pos;
          fail(fmt::format("duplicate key \"{}\"", key));
        }
        skip_space();
        expect(':', "':' after an object key");
        skip_space();
        JsonValue member = value(depth + 1);
        v.members_.emplace_back(std::move(key), std::move(member));
        skip_space();
        if (peek() == ',') {
          ++pos_;
          continue;
        }
        expect('}', "',' or '}' in an object");
        return v;
      }
    }
    if (c == '[') {
      v.type_ = JsonValue::Type::kArray;
      ++pos_;
      skip_space();
      if (peek() == ']') {
        ++pos_;
        return v;
      }
      for (;;) {
        skip_space();
        v.items_.push_back(value(depth + 1));
        skip_space();
        if (peek() == ',') {
          ++pos_;
          continue;
        }
        expect(']', "',' or ']' in an array");
        return v;
      }
    }
    if (c == '"') {
      v.type_ = JsonValue::Type::kString;
      v.string_ = string();
      return v;
    }
    if (c == '-' || (c >= '0' && c <= '9')) {
      v.type_ = JsonValue::Type::kNumber;
      v.number_ = number();
      return v;
    }
    for (const char* word : {"true", "false", "null"}) {
      const std::string_view w(word);
      if (text_.substr(pos_, w.size()) == w) {
        pos_ += w.size();
        if (w == "null") return v;
        v.type_ = JsonValue::Type::kBool;
        v.boolean_ = w == "true";
        return v;
      }
    }
    fail(fmt::format("'{}' does not start a JSON value", c));
  }

  static bool digit(char c) { return c >= '0' && c <= '9'; }

  double number() {
    const size_t start = pos_;
    if (peek() == '-') ++pos_;
    if (peek() == '0') {
      ++pos_;
      if (digit(peek())) fail("a number must not have leading zeros");
    } else if (digit(peek())) {
      while (digit(peek())) ++pos_;
    } else {
      fail("a digit must follow '-'");
    }
    if (peek() == '.') {
      ++pos_;
      if (!digit(peek())) fail("a digit must follow the decimal point");
      while (digit(peek())) ++pos_;
    }
    if (peek() == 'e' || peek() == 'E') {
      ++pos_;
      if (peek() == '+' || peek() == '-') ++pos_;
      if (!digit(peek())) fail("a digit must follow the exponent");
      while (digit(peek())) ++pos_;
    }
    const std::string token(text_.substr(start, pos_ - start));
    errno = 0;
    const double x = std::strtod(token.c_str(), nullptr);
    if (!std::isfinite(x)) {
      pos_ = start;
      fail(fmt::format("number {} is out of range", token));
    }
    return x;
  }

  unsigned hex4() {
    unsigned u = 0;
    for (int i = 0; i < 4; ++i) {
      const char h = peek();
      unsigned d;
      if (h >= '0' && h <= '9') {
        d = static_cast<unsigned>(h - '0');
      } else if (h >= 'a' && h <= 'f') {
        d = static_cast<unsigned>(h - 'a' + 10);
      } else if (h >= 'A' && h <= 'F') {
        d = static_cast<unsigned>(h - 'A' + 10);
      } else {
        fail("\\u must be followed by four hexadecimal digits");
      }
      u = u * 16 + d;
      ++pos_;
    }
    return u;
  }

  static void append_utf8(std::string& s, unsigned cp) {
    if (cp < 0x80) {
      s += static_cast<char>(cp);
    } else if (cp < 0x800) {
      s += static_cast<char>(0xC0 | (cp >> 6));
      s += static_cast<char>(0x80 | (cp & 0x3F));
    } else if (cp < 0x10000) {
      s += static_cast<char>(0xE0 | (cp >> 12));
      s += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
      s += static_cast<char>(0x80 | (cp & 0x3F));
    } else {
      s += static_cast<char>(0xF0 | (cp >> 18));
      s += static_cast<char>(0x80 | ((cp >> 12) & 0x3F));
      s += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
      s += static_cast<char>(0x80 | (cp & 0x3F));
    }
  }

  std::string string() {
    ++pos_;  // the opening quote
    std::string s;
    for (;;) {
      if (at_end()) fail("end of file inside a string");
      const char c = peek();
      if (c == '"') {
        ++pos_;
        return s;
      }
      if (static_cast<unsigned char>(c) < 0x20) fail("control character inside a string");
      if (c != '\\') {
        s += c;
        ++pos_;
        continue;
      }
      ++pos_;
      const char e = peek();
      ++pos_;
      switch (e) {
        case '"':
          s += '"';
          break;
        case '\\':
          s += '\\';
          break;
        case '/':
          s += '/';
          break;
        case 'b':
          s += '\b';
          break;
        case 'f':
          s += '\f';
          break;
        case 'n':
          s += '\n';
          break;
        case 'r':
          s += '\r';
          break;
        case 't':
          s += '\t';
          break;
        case 'u': {
          unsigned cp = hex4();
          if (cp >= 0xD800 && cp < 0xDC00) {
            if (text_.substr(pos_, 2) != "\\u") fail("unpaired UTF-16 surrogate");
            pos_ += 2;
            const unsigned lo = hex4();
            if (lo < 0xDC00 || lo >= 0xE000) fail("unpaired UTF-16 surrogate");
            cp = 0x10000 + ((cp - 0xD800) << 10) + (lo - 0xDC00);
          } else if (cp >= 0xDC00 && cp < 0xE000) {
            fail("unpaired UTF-16 surrogate");
          }
          append_utf8(s, cp);
          break;
        }
        default:
          --pos_;
          fail("unknown escape in a string");
      }
    }
  }

  std::string_view text_;
  const std::string& name_;
  size_t pos_ = 0;
};

JsonValue parse_json(std::string_view text, const std::string& name) {
  return JsonParser(text, name).document();
}

JsonValue read_json(const std::filesystem::path& path) {
  require_regular_file(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(fmt::format("{}: cannot open the file", path.string()));
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw InputError(fmt::format("{}: cannot read the file", path.string()));
  return parse_json(ss.str(), path.string());
}

}  // namespace jointlab::data
