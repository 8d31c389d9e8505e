#include "jointlab/data/mat_file.h"

#include "jointlab/core/text.h"
#include "jointlab/core/units.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include <fmt/format.h>
#include <matio.h>
#include <unistd.h>
#include <zlib.h>

#include "jointlab/core/error.h"
#include "jointlab/data/mat_variable.h"
#include "jointlab/data/names.h"

namespace jointlab::data {

std::optional<size_t> mat_element_count(const matvar_t* v) {
  if (!v || v->rank < 0 || v->rank > 32 || (v->rank > 0 && !v->dims)) return std::nullopt;
  size_t n = 1;
  for (int i = 0; i < v->rank; ++i) {
    if (v->dims[i] != 0 && n > SIZE_MAX / v->dims[i]) return std::nullopt;
    n *= v->dims[i];
  }
  return n;
}

std::optional<std::string> mat_char_text(const matvar_t* v) {
  if (!v || v->class_type != MAT_C_CHAR) return std::nullopt;
  const auto n = mat_element_count(v);
  if (!n) return std::nullopt;
  if (*n == 0) return std::string();
  const size_t size = Mat_SizeOf(v->data_type);
  if (!v->data || (size != 1 && size != 2 && size != 4) || v->nbytes < *n * size) {
    return std::nullopt;
  }
  const size_t rows = v->rank >= 1 ? v->dims[0] : 1;
  const size_t cols = rows ? *n / rows : 0;
  std::string out;
  for (size_t r = 0; r < rows; ++r) {
    if (r) out += '\n';
    for (size_t c = 0; c < cols; ++c) {
      const size_t i = r + rows * c;
      uint32_t code = 0;
      if (size == 1) code = static_cast<const uint8_t*>(v->data)[i];
      if (size == 2) code = static_cast<const uint16_t*>(v->data)[i];
      if (size == 4) code = static_cast<const uint32_t*>(v->data)[i];
      out += code >= 0x20 && code < 0x7f ? static_cast<char>(code) : '?';
    }
  }
  return out;
}

namespace {

// matio reports problems through a log function; keep its last word for our messages
// instead of letting it print.
thread_local std::string g_matio_message;

void matio_log(int level, char* message) {
  if ((level & (MATIO_LOG_LEVEL_ERROR | MATIO_LOG_LEVEL_CRITICAL)) && message) {
    g_matio_message = message;
  }
}

void quiet_matio() {
  static std::once_flag once;
  std::call_once(once, [] { Mat_LogInitFunc("jointlab", matio_log); });
  g_matio_message.clear();
}

std::string matio_says() {
  return g_matio_message.empty() ? std::string() : fmt::format(" ({})", g_matio_message);
}

struct MatCloser {
  void operator()(mat_t* m) const { Mat_Close(m); }
};
struct VarFreer {
  void operator()(matvar_t* v) const { Mat_VarFree(v); }
};
using MatPtr = std::unique_ptr<mat_t, MatCloser>;
using VarPtr = std::unique_ptr<matvar_t, VarFreer>;

// Deflate cannot compress by more than about 1032:1; a variable whose declared size
// exceeds that much of the file is a lie, refused before anything is allocated.
constexpr double kMaxExpansion = 1100.0;

bool is_numeric(const matvar_t* v) {
  switch (v->class_type) {
    case MAT_C_DOUBLE:
    case MAT_C_SINGLE:
    case MAT_C_INT8:
    case MAT_C_UINT8:
    case MAT_C_INT16:
    case MAT_C_UINT16:
    case MAT_C_INT32:
    case MAT_C_UINT32:
    case MAT_C_INT64:
    case MAT_C_UINT64:
      return !v->isLogical;
    default:
      return false;
  }
}

size_t class_size(const matvar_t* v) { return Mat_SizeOfClass(v->class_type); }

// Declared data size of a variable (a struct: the sum over its fields), or nullopt when it
// overflows or nests too deep.
std::optional<double> declared_bytes(const matvar_t* v, int depth = 0) {
  if (depth > 8) return std::nullopt;
  const auto n = mat_element_count(v);
  if (!n) return std::nullopt;
  if (v->class_type == MAT_C_STRUCT) {
    const unsigned nfields = Mat_VarGetNumberOfFields(const_cast<matvar_t*>(v));
    double sum = 0;
    auto** fields = static_cast<matvar_t**>(v->data);
    if (!fields) return 0.0;
    const double count = static_cast<double>(*n) * nfields;
    if (count > 1e7) return std::nullopt;
    for (size_t i = 0; i < static_cast<size_t>(count); ++i) {
      if (!fields[i]) continue;
      const auto b = declared_bytes(fields[i], depth + 1);
      if (!b) return std::nullopt;
      sum += *b;
    }
    return sum;
  }
  if (v->class_type == MAT_C_CELL) return static_cast<double>(*n) * 64;
  return static_cast<double>(*n) * std::max<size_t>(class_size(v), 1);
}

// Numeric data of a read variable as doubles; nullopt when it has none.
std::optional<std::vector<double>> numeric_data(const matvar_t* v) {
  const auto n = mat_element_count(v);
  if (!n || !v->data || !is_numeric(v) || v->isComplex) return std::nullopt;
  const size_t size = class_size(v);
  if (size == 0 || v->nbytes < *n * size) return std::nullopt;
  std::vector<double> out(*n);
  const void* d = v->data;
  for (size_t i = 0; i < *n; ++i) {
    switch (v->class_type) {
      case MAT_C_DOUBLE:
        out[i] = static_cast<const double*>(d)[i];
        break;
      case MAT_C_SINGLE:
        out[i] = static_cast<const float*>(d)[i];
        break;
      case MAT_C_INT8:
        out[i] = static_cast<const int8_t*>(d)[i];
        break;
      case MAT_C_UINT8:
        out[i] = static_cast<const uint8_t*>(d)[i];
        break;
      case MAT_C_INT16:
        out[i] = static_cast<const int16_t*>(d)[i];
        break;
      case MAT_C_UINT16:
        out[i] = static_cast<const uint16_t*>(d)[i];
        break;
      case MAT_C_INT32:
        out[i] = static_cast<const int32_t*>(d)[i];
        break;
      case MAT_C_UINT32:
        out[i] = static_cast<const uint32_t*>(d)[i];
        break;
      case MAT_C_INT64:
        out[i] = static_cast<double>(static_cast<const int64_t*>(d)[i]);
        break;
      case MAT_C_UINT64:
        out[i] = static_cast<double>(static_cast<const uint64_t*>(d)[i]);
        break;
      default:
        return std::nullopt;
    }
  }
  return out;
}

// A char row or a cell of char rows as a list of strings.
std::optional<std::vector<std::string>> string_list(const matvar_t* v, bool split_commas) {
  if (!v) return std::nullopt;
  std::vector<std::string> out;
  if (v->class_type == MAT_C_CHAR) {
    auto text = mat_char_text(v);
    if (!text) return std::nullopt;
    if (!split_commas) return std::vector<std::string>{*text};
    size_t pos = 0;
    while (true) {
      const size_t comma = text->find(',', pos);
      std::string item = text->substr(pos, comma == std::string::npos ? comma : comma - pos);
      const auto a = item.find_first_not_of(" \t");
      const auto b = item.find_last_not_of(" \t");
      out.push_back(a == std::string::npos ? std::string() : item.substr(a, b - a + 1));
      if (comma == std::string::npos) break;
      pos = comma + 1;
    }
    return out;
  }
  if (v->class_type == MAT_C_CELL) {
    const auto n = mat_element_count(v);
    if (!n || *n > 100000 || !v->data) return std::nullopt;
    for (size_t i = 0; i < *n; ++i) {
      const matvar_t* cell = static_cast<matvar_t* const*>(v->data)[i];
      auto text = mat_char_text(cell);
      if (!text) return std::nullopt;
      out.push_back(*text);
    }
    return out;
  }
  return std::nullopt;
}

bool is_vector(const matvar_t* v, size_t& length) {
  const auto n = mat_element_count(v);
  if (!n || v->rank > 2) return false;
  if (v->rank == 2 && v->dims[0] != 1 && v->dims[1] != 1) return false;
  length = *n;
  return true;
}

struct Named {
  std::string name;
  const matvar_t* var;
};

bool is_time_name(const std::string& n) { return lower(n) == "time" || n == "t"; }

double scalar_field(const Named& f, const std::string& file, const std::string& prefix) {
  size_t len = 0;
  const auto data = numeric_data(f.var);
  if (!data || !is_vector(f.var, len) || len != 1) {
    throw InputError(
        where(file, 0, fmt::format("field '{}{}' is not a real numeric scalar", prefix, f.name)));
  }
  return (*data)[0];
}

// "the file " or "struct 'name' " for messages about a missing part.
std::string holder(const std::string& prefix) {
  return prefix.empty() ? "the file " : "struct '" + prefix.substr(0, prefix.size() - 1) + "' ";
}

// The fields of a struct (or the top-level variables) sorted by their role.
struct Fields {
  const Named* time = nullptr;
  const Named* fs = nullptr;
  const Named* t0 = nullptr;
  const Named* units = nullptr;
  const Named* names = nullptr;
  std::vector<const Named*> channels;
  size_t n = 0;  // samples per channel
};

// A numeric field: a channel (vector of 2 or more samples), metadata (scalar) or ignored.
void classify_numeric(const Named& v, const std::string& file, const std::string& prefix, Fields& f,
                      Record& rec, std::vector<std::string>& ignored) {
  const std::string field = prefix + v.name;
  const auto count = mat_element_count(v.var);
  if (count && *count > 0 && !v.var->data) {
    throw InputError(where(file, 0,
                           fmt::format("field '{}': data could not be read (truncated "
                                       "or damaged file){}",
                                       field, matio_says())));
  }
  size_t len = 0;
  const bool vec = is_vector(v.var, len);
  if (vec && len >= 2) {
    if (v.var->isComplex) {
      throw InputError(where(file, 0,
                             fmt::format("field '{}' is complex; a time history is "
                                         "real",
                                         field)));
    }
    if (!f.channels.empty() && len != f.n) {
      throw InputError(where(file, 0,
                             fmt::format("field '{}' has {} samples, field '{}{}' "
                                         "{}: channels must share one time base",
                                         field, len, prefix, f.channels[0]->name, f.n)));
    }
    f.n = len;
    f.channels.push_back(&v);
  } else if (vec && len == 1 && !v.var->isComplex) {
    if (auto d = numeric_data(v.var)) rec.metadata[v.name] = fmt::format("{}", (*d)[0]);
  } else {
    ignored.push_back(v.name);
  }
}

// Sorts the fields by role; scalars and text lines go to rec.metadata, the rest is listed
// under "ignored".
Fields classify_fields(const std::vector<Named>& vars, const std::string& file,
                       const std::string& prefix, Record& rec) {
  Fields f;
  std::vector<std::string> ignored;
  for (const Named& v : vars) {
    if (!v.var) continue;
    if (is_time_name(v.name) && !f.time && is_numeric(v.var)) {
      f.time = &v;
    } else if (lower(v.name) == "fs") {
      f.fs = &v;
    } else if (v.name == "t0") {
      f.t0 = &v;
    } else if (lower(v.name) == "units") {
      f.units = &v;
    } else if (v.name == "channel_names") {
      f.names = &v;
    } else if (is_numeric(v.var)) {
      classify_numeric(v, file, prefix, f, rec, ignored);
    } else if (v.var->class_type == MAT_C_CHAR) {
      if (auto text = mat_char_text(v.var); text && text->find('\n') == std::string::npos) {
        rec.metadata[v.name] = *text;
      } else {
        ignored.push_back(v.name);
      }
    } else {
      ignored.push_back(v.name);
    }
  }
  if (f.channels.empty()) {
    throw InputError(where(file, 0,
                           fmt::format("no channel: {}holds no real numeric vector "
                                       "besides the time base",
                                       holder(prefix))));
  }
  if (!ignored.empty()) {
    std::string list;
    for (const auto& s : ignored) list += (list.empty() ? "" : ", ") + s;
    rec.metadata["ignored"] = list;
  }
  return f;
}

// The channel units of the 'units' field (one for all or one each) and the time unit's
// factor to seconds (the first entry when there is a time vector).
struct Units {
  std::vector<std::string> channel;
  double time_scale = 1.0;
};

Units read_units(const Fields& f, const std::string& file, const std::string& prefix) {
  Units out;
  if (!f.units) return out;
  const std::string& name = f.units->name;
  auto list = string_list(f.units->var, true);
  if (!list) {
    throw InputError(where(file, 0,
                           fmt::format("field '{}{}' is not text (a char row or a cell"
                                       " of strings)",
                                       prefix, name)));
  }
  out.channel = *list;
  const size_t nc = f.channels.size();
  if (f.time) {
    if (out.channel.size() != nc + 1 && out.channel.size() != 2) {
      throw InputError(where(file, 0,
                             fmt::format("field '{}{}' has {} entries; expected the "
                                         "time unit and then 1 or {} channel units",
                                         prefix, name, out.channel.size(), nc)));
    }
    const std::string tu = out.channel.front();
    out.channel.erase(out.channel.begin());
    if (tu == "ms") {
      out.time_scale = 1e-3;
    } else if (!tu.empty() && tu != "s") {
      throw InputError(where(
          file, 0, fmt::format("field '{}{}': time unit '{}' is not s or ms", prefix, name, tu)));
    }
  } else if (out.channel.size() != nc && out.channel.size() != 1) {
    throw InputError(where(file, 0,
                           fmt::format("field '{}{}' has {} entries; expected 1 or {} "
                                       "channel units",
                                       prefix, name, out.channel.size(), nc)));
  }
  return out;
}

// The time vector in seconds, checked finite, increasing and uniform; returns its step.
double time_vector_step(const Named& time, size_t n, double time_scale, const std::string& file,
                        const std::string& prefix, double& t_first) {
  const std::string field = prefix + time.name;
  size_t len = 0;
  auto t = numeric_data(time.var);
  if (!t || !is_vector(time.var, len)) {
    throw InputError(where(file, 0, fmt::format("field '{}' is not a real numeric vector", field)));
  }
  if (len != n) {
    throw InputError(
        where(file, 0, fmt::format("field '{}' has {} samples, the channels {}", field, len, n)));
  }
  for (double& x : *t) x *= time_scale;
  for (size_t k = 0; k < n; ++k) {
    if (!std::isfinite((*t)[k])) {
      throw InputError(
          where(file, 0, fmt::format("field '{}': sample {} is {}", field, k + 1, (*t)[k])));
    }
    if (k > 0 && !((*t)[k] > (*t)[k - 1])) {
      throw InputError(where(file, 0,
                             fmt::format("field '{}': time {} at sample {} does not "
                                         "increase (previous {})",
                                         field, (*t)[k], k + 1, (*t)[k - 1])));
    }
  }
  const double dt = ((*t)[n - 1] - (*t)[0]) / static_cast<double>(n - 1);
  for (size_t k = 0; k < n; ++k) {
    const double expected = (*t)[0] + static_cast<double>(k) * dt;
    if (std::abs((*t)[k] - expected) > 0.1 * dt) {
      throw InputError(where(file, 0,
                             fmt::format("field '{}': time step is not uniform: t = {}"
                                         " at sample {} where {} was expected",
                                         field, (*t)[k], k + 1, expected)));
    }
  }
  if (!std::isfinite(1.0 / dt)) {
    throw InputError(where(file, 0, fmt::format("field '{}': no usable time step", field)));
  }
  t_first = (*t)[0];
  return dt;
}

// Sets rec.fs and rec.t0 from the 'time' vector, the 'fs' and 't0' scalars.
void set_time_base(Record& rec, const Fields& f, double time_scale, const std::string& file,
                   const std::string& prefix) {
  std::optional<double> fs_value;
  if (f.fs) {
    fs_value = scalar_field(*f.fs, file, prefix);
    if (!std::isfinite(*fs_value) || *fs_value <= 0) {
      throw InputError(where(file, 0,
                             fmt::format("field '{}{}': {} Hz is not a positive sampling "
                                         "rate",
                                         prefix, f.fs->name, *fs_value)));
    }
  }
  if (f.t0) {
    rec.t0 = scalar_field(*f.t0, file, prefix);
    if (!std::isfinite(rec.t0)) {
      throw InputError(
          where(file, 0, fmt::format("field '{}{}' is not finite", prefix, f.t0->name)));
    }
  }
  if (f.time) {
    double t_first = 0;
    const double dt = time_vector_step(*f.time, f.n, time_scale, file, prefix, t_first);
    if (fs_value && std::abs(*fs_value - 1.0 / dt) > 1e-3 * *fs_value) {
      throw InputError(
          where(file, 0,
                fmt::format("field '{}{}' = {} Hz disagrees with field '{}{}' "
                            "({} Hz)",
                            prefix, f.fs->name, *fs_value, prefix, f.time->name, 1.0 / dt)));
    }
    rec.fs = fs_value ? *fs_value : 1.0 / dt;
    if (!f.t0) rec.t0 = t_first;
  } else if (fs_value) {
    rec.fs = *fs_value;
  } else {
    throw InputError(where(file, 0,
                           fmt::format("no time base: {}has no 'time' vector and no 'fs'"
                                       " scalar",
                                       holder(prefix))));
  }
}

// One channel field as an SI channel named from 'channel_names' (or the field).
Channel make_channel(const Named& v, const std::string& name, const std::string& unit_text,
                     const Fields& f, const std::string& file, const std::string& prefix) {
  const std::string field = prefix + v.name;
  auto data = numeric_data(v.var);
  if (!data || data->size() != f.n) {
    throw InputError(
        where(file, 0, fmt::format("field '{}': data could not be read{}", field, matio_says())));
  }
  for (size_t k = 0; k < f.n; ++k) {
    if (!std::isfinite((*data)[k])) {
      throw InputError(where(file, 0,
                             fmt::format("field '{}': sample {} is {} (NaN and Inf are"
                                         " not allowed)",
                                         field, k + 1, (*data)[k])));
    }
  }
  Channel ch;
  ch.name = name;
  double scale = 1.0;
  if (!unit_text.empty()) {
    const auto unit = parse_unit(unit_text);
    if (!unit) {
      throw InputError(
          where(file, 0,
                fmt::format("field '{}{}': unknown unit '{}' for "
                            "channel '{}' (known: {})",
                            prefix, f.units->name, unit_text, ch.name, known_units())));
    }
    ch.quantity = unit->quantity;
    ch.unit = unit_text;
    scale = unit->to_si;
  }
  ch.samples =
      Eigen::Map<const Eigen::VectorXd>(data->data(), static_cast<Eigen::Index>(f.n)) * scale;
  return ch;
}

// Builds the record from the fields of a struct (or the top-level variables).
Record build_record(const std::vector<Named>& vars, const std::string& file,
                    const std::string& prefix) {
  Record rec;
  rec.source = file;
  const Fields f = classify_fields(vars, file, prefix, rec);
  const Units units = read_units(f, file, prefix);
  set_time_base(rec, f, units.time_scale, file, prefix);

  std::vector<std::string> channel_names;
  if (f.names) {
    auto list = string_list(f.names->var, false);
    if (list && list->size() == f.channels.size()) channel_names = *list;
  }
  for (size_t c = 0; c < f.channels.size(); ++c) {
    const Named& v = *f.channels[c];
    const std::string name =
        channel_names.empty() || channel_names[c].empty() ? v.name : channel_names[c];
    const std::string unit = units.channel.empty()       ? std::string()
                             : units.channel.size() == 1 ? units.channel[0]
                                                         : units.channel[c];
    Channel ch = make_channel(v, name, unit, f, file, prefix);
    for (const Channel& other : rec.channels) {
      if (other.name == ch.name) {
        throw InputError(where(
            file, 0, fmt::format("field '{}{}': two channels named '{}'", prefix, v.name, name)));
      }
    }
    rec.channels.push_back(std::move(ch));
  }
  std::vector<std::string> names;
  for (const Channel& ch : rec.channels) names.push_back(ch.name);
  check_channel_names(names, file);
  return rec;
}

bool has_hdf5_signature(const std::filesystem::path& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  char sig[8] = {};
  const bool ok = std::fseek(f, 512, SEEK_SET) == 0 && std::fread(sig, 1, 8, f) == 8;
  std::fclose(f);
  return ok && std::memcmp(sig, "\x89HDF\r\n\x1a\n", 8) == 0;
}

// ---------------------------------------------------------------------------------------------
// A structural check of v5 files before matio sees them: matio allocates what a tag
// declares (names, cell and struct arrays) before it knows the bytes are there, so every
// tag, name, cell and field count is checked against the bytes that hold it first.

class V5Check {
 public:
  V5Check(const std::string& file, bool swap, double budget)
      : file_(file), swap_(swap), budget_(budget) {}

  // Top level: a sequence of (possibly compressed) data elements, 8-byte aligned.
  void top(const unsigned char* p, size_t n) {
    size_t off = 0;
    int count = 0;
    while (off < n) {
      if (n - off < 8) break;  // trailing padding
      if (++count > 10000) fail(off, "more than 10000 variables");
      off += element(p + off, n - off, 0, true);
    }
  }

 private:
  [[noreturn]] void fail(size_t off, const std::string& what) const {
    throw InputError(
        where(file_, 0, fmt::format("not a valid MATLAB v5 file: {} (near byte {})", what, off)));
  }
  uint32_t u32(const unsigned char* p) const {
    uint32_t v;
    std::memcpy(&v, p, 4);
    return swap_ ? __builtin_bswap32(v) : v;
  }

  // One variable (an array, or a compressed array) at p, n bytes available; returns the
  // bytes it occupies.
  size_t element(const unsigned char* p, size_t n, int depth, bool top_level) {
    if (n < 8) fail(0, "truncated data element");
    const uint32_t w0 = u32(p);
    const uint32_t type = w0;
    if (type != 14 && type != 15)
      fail(0, fmt::format("variable of data type {} is not an array", type));
    const uint32_t bytes = u32(p + 4);
    if (bytes > n - 8) {
      fail(0, fmt::format("element of type {} declares {} bytes, {} remain", type, bytes, n - 8));
    }
    if (type == 14) matrix(p + 8, bytes, depth + 1);
    if (type == 15) {
      if (!top_level) fail(0, "compressed element inside a variable");
      inflate_and_check(p + 8, bytes, depth);
      return 8 + bytes;  // compressed elements are not padded
    }
    const size_t padded = 8 + ((static_cast<size_t>(bytes) + 7) / 8) * 8;
    return std::min(padded, n);
  }

  void inflate_and_check(const unsigned char* p, size_t n, int depth) {
    // Deflate expands at most ~1032:1; the budget bounds what a lying stream can cost.
    std::vector<unsigned char> out;
    z_stream z{};
    if (inflateInit(&z) != Z_OK) fail(0, "zlib initialisation failed");
    z.next_in = const_cast<unsigned char*>(p);
    z.avail_in = static_cast<uInt>(std::min<size_t>(n, UINT32_MAX));
    int rc = Z_OK;
    while (rc == Z_OK) {
      if (static_cast<double>(out.size()) >= budget_) {
        inflateEnd(&z);
        fail(0, "compressed variable expands beyond any plausible size");
      }
      const size_t chunk = std::min<size_t>(std::max<size_t>(out.size(), 1 << 16), 1 << 24);
      const size_t old = out.size();
      out.resize(old + chunk);
      z.next_out = out.data() + old;
      z.avail_out = static_cast<uInt>(chunk);
      rc = inflate(&z, Z_NO_FLUSH);
      out.resize(old + chunk - z.avail_out);
      if (rc == Z_BUF_ERROR && z.avail_in == 0) break;  // stream ends early: truncated
      if (rc == Z_BUF_ERROR) rc = Z_OK;
    }
    inflateEnd(&z);
    if (rc != Z_STREAM_END) fail(0, "compressed variable is damaged or truncated");
    if (out.size() < 8) fail(0, "empty compressed variable");
    element(out.data(), out.size(), depth, false);
  }

  struct Tag {
    uint32_t type, bytes;
    size_t header;  // 4 (small element) or 8
    size_t total;   // bytes the element occupies, padding included
  };
  // The tag of the element at p; fails unless the element fits in n bytes.
  Tag tag(const unsigned char* p, size_t n, bool padded = true) const {
    if (n < 8) fail(0, "truncated data element");
    const uint32_t w0 = u32(p);
    if (w0 >> 16) {
      if ((w0 >> 16) > 4) fail(0, "small data element larger than 4 bytes");
      return Tag{w0 & 0xffff, w0 >> 16, 4, 8};
    }
    const uint32_t bytes = u32(p + 4);
    if (bytes > n - 8)
      fail(0, fmt::format("element of type {} declares {} bytes, {} remain", w0, bytes, n - 8));
    const size_t total = padded ? std::min(n, 8 + ((static_cast<size_t>(bytes) + 7) / 8) * 8)
                                : 8 + static_cast<size_t>(bytes);
    return Tag{w0, bytes, 8, total};
  }

  static size_t type_size(uint32_t t) {
    switch (t) {
      case 1:
      case 2:
      case 16:
        return 1;  // int8, uint8, utf8
      case 3:
      case 4:
      case 17:
        return 2;  // int16, uint16, utf16
      case 5:
      case 6:
      case 7:
      case 18:
        return 4;  // int32, uint32, single, utf32
      case 9:
      case 12:
      case 13:
        return 8;  // double, int64, uint64
      default:
        return 0;
    }
  }

  // The sub-elements of an miMATRIX element, held to the layout MATLAB, scipy and matio
  // write: flags, dimensions, name, then the class's own parts, each fitting its bytes.
  void matrix(const unsigned char* p, size_t n, int depth) {
    if (depth > 16) fail(0, "variables nested more than 16 deep");
    if (n == 0) return;  // an empty cell or field
    size_t off = 0;
    auto next = [&](const char* what) {
      if (n - std::min(off, n) < 8) fail(off, fmt::format("array {} missing", what));
      const Tag t = tag(p + off, n - off);
      const unsigned char* data = p + off + t.header;
      off += t.total;
      return std::make_pair(t, data);
    };
    const auto [flags, flag_data] = next("flags");
    if (flags.type != 6 || flags.bytes != 8) fail(off, "array flags are not 8 bytes of uint32");
    const uint32_t class_type = u32(flag_data) & 0xff;
    const bool complex = u32(flag_data) & 0x800;
    const auto [dims, dim_data] = next("dimensions");
    if (dims.type != 5 || dims.bytes < 8 || dims.bytes % 4) fail(off, "bad array dimensions");
    double count = 1;
    for (uint32_t i = 0; i < dims.bytes / 4; ++i) {
      const auto v = static_cast<int32_t>(u32(dim_data + 4 * i));
      if (v < 0) fail(off, "negative dimension");
      count *= v;
    }
    const auto [name, name_data] = next("name");
    if (name.type != 1 && name.type != 2) fail(off, "array name is not text");
    auto sub_matrices = [&](double expected) {
      if (expected * 8 > static_cast<double>(n - std::min(off, n))) {
        fail(off, "cell or struct array larger than its bytes");
      }
      for (double k = 0; k < expected; ++k) {
        const Tag t = tag(p + off, n - std::min(off, n));
        if (t.header != 8 || t.type != 14) fail(off, "cell or field is not an array");
        matrix(p + off + 8, t.bytes, depth + 1);
        off += t.total;
      }
    };
    switch (class_type) {
      case 1:  // cell
        sub_matrices(count);
        break;
      case 2: {  // struct: field name length, field names, then the fields of every element
        const auto [len_tag, len_data] = next("field name length");
        if (len_tag.type != 5 || len_tag.bytes != 4) fail(off, "bad struct field name length");
        const uint32_t len = u32(len_data);
        const auto [names, names_data] = next("field names");
        if (names.type != 1 || (len == 0 && names.bytes != 0) || (len != 0 && names.bytes % len) ||
            len > 4096) {
          fail(off, "bad struct field names");
        }
        sub_matrices(len ? count * (names.bytes / len) : 0);
        break;
      }
      case 4:
      case 6:
      case 7:
      case 8:
      case 9:
      case 10:
      case 11:
      case 12:
      case 13:
      case 14:
      case 15: {
        // char and numeric: real (and imaginary) part, each exactly count values
        if (count * 16 > budget_) fail(off, "array larger than any plausible file");
        for (int part = 0; part < (complex ? 2 : 1); ++part) {
          if (count == 0 && n - std::min(off, n) < 8) break;
          const auto [data, data_bytes] = next("data");
          (void)data_bytes;
          const size_t size = type_size(data.type);
          if (size == 0 || static_cast<double>(data.bytes) != count * static_cast<double>(size)) {
            fail(off, fmt::format("array data of type {} holds {} bytes for {} values", data.type,
                                  data.bytes, count));
          }
        }
        break;
      }
      default:
        fail(off, fmt::format("variable of class {} (object, sparse, function or opaque) is not "
                              "read",
                              class_type));
    }
  }

  const std::string& file_;
  bool swap_;
  double budget_;
};

// Reads the file and checks it is a v5 file whose structure holds together, or a v7.3
// (HDF5) file; anything else (MAT v4, garbage) is refused here.
void check_mat_file(const std::filesystem::path& path, double budget) {
  const std::string file = path.string();
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(where(file, 0, "cannot open file"));
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (bytes.size() < 128) throw InputError(where(file, 0, "too short for a MATLAB .mat file"));
  const auto* u = reinterpret_cast<const unsigned char*>(bytes.data());
  const bool le = u[126] == 'I' && u[127] == 'M';
  const bool be = u[126] == 'M' && u[127] == 'I';
  if (!le && !be) {
    throw InputError(where(file, 0,
                           "not a MATLAB v5/v7/v7.3 .mat file (no MAT-file header; "
                           "MAT v4 files are not read)"));
  }
  const bool swap = be == (std::endian::native == std::endian::little);
  const uint16_t version = swap ? static_cast<uint16_t>(u[124] << 8 | u[125])
                                : static_cast<uint16_t>(u[125] << 8 | u[124]);
  if (version == 0x0200) return;  // v7.3: HDF5 does its own checking
  if (version != 0x0100) {
    throw InputError(
        where(file, 0, fmt::format("MAT-file version 0x{:04x} is not 5 or 7.3", version)));
  }
  V5Check(file, swap, budget).top(u + 128, bytes.size() - 128);
}

}  // namespace

Record read_mat(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::error_code ec;
  const auto file_size = std::filesystem::file_size(path, ec);
  if (ec) throw InputError(where(file, 0, "cannot open file"));
  if (file_size < 128) throw InputError(where(file, 0, "too short for a MATLAB .mat file"));
  check_mat_file(path, static_cast<double>(file_size) * kMaxExpansion + 1e6);
  quiet_matio();
  MatPtr mat(Mat_Open(file.c_str(), MAT_ACC_RDONLY));
  if (!mat) {
    if (has_hdf5_signature(path) && !mat_v73_supported()) {
      throw InputError(where(file, 0,
                             "MATLAB v7.3 (HDF5) file, and the matio library here was "
                             "built without HDF5: save it with -v7 instead"));
    }
    throw InputError(
        where(file, 0, fmt::format("not a MATLAB .mat file that matio can open{}", matio_says())));
  }
  const double budget = static_cast<double>(file_size) * kMaxExpansion + 1e6;

  // The directory: names, classes and sizes, no data yet.
  std::vector<VarPtr> infos;
  while (true) {
    VarPtr info(Mat_VarReadNextInfo(mat.get()));
    if (!info) break;
    if (infos.size() >= 10000) {
      throw InputError(where(file, 0, "more than 10000 variables; not a test record"));
    }
    if (!info->name) continue;
    infos.push_back(std::move(info));
  }
  if (infos.empty()) {
    throw InputError(where(file, 0, fmt::format("no variables in this .mat file{}", matio_says())));
  }

  // Which variables form the record.
  bool top_level = false;
  for (const VarPtr& v : infos) {
    const std::string n = v->name;
    if ((is_time_name(n) || lower(n) == "fs") && is_numeric(v.get())) top_level = true;
  }
  std::vector<std::string> candidates;
  if (!top_level) {
    for (const VarPtr& v : infos) {
      if (v->class_type != MAT_C_STRUCT) continue;
      const unsigned nf = Mat_VarGetNumberOfFields(v.get());
      char* const* fields = Mat_VarGetStructFieldnames(v.get());
      bool has_time = false;
      for (unsigned i = 0; fields && i < nf; ++i) {
        if (fields[i] && (is_time_name(fields[i]) || lower(fields[i]) == "fs")) has_time = true;
      }
      if (has_time) candidates.push_back(v->name);
    }
    if (candidates.empty()) {
      std::string list;
      for (const VarPtr& v : infos) list += (list.empty() ? "" : ", ") + std::string(v->name);
      throw InputError(where(file, 0,
                             fmt::format("no time histories found: no struct with a "
                                         "'time' or 'fs' field and no top-level 'time' "
                                         "or 'fs' variable (variables: {})",
                                         list)));
    }
    if (candidates.size() > 1) {
      throw InputError(where(file, 0,
                             fmt::format("structs '{}' and '{}' both hold a time base; "
                                         "jointlab reads one record per file",
                                         candidates[0], candidates[1])));
    }
  }

  std::vector<VarPtr> owned;
  std::vector<Named> vars;
  std::string prefix;
  for (const VarPtr& info : infos) {
    const std::string name = info->name;
    if (!top_level && name != candidates.front()) continue;
    const auto bytes = declared_bytes(info.get());
    if (!bytes || *bytes > budget) {
      throw InputError(where(file, 0,
                             fmt::format("variable '{}' declares more data than a {} "
                                         "byte file can hold",
                                         name, file_size)));
    }
    VarPtr var(Mat_VarRead(mat.get(), name.c_str()));
    if (!var) {
      throw InputError(
          where(file, 0, fmt::format("variable '{}' could not be read{}", name, matio_says())));
    }
    if (top_level) {
      vars.push_back(Named{name, var.get()});
    } else {
      const auto n = mat_element_count(var.get());
      if (var->class_type != MAT_C_STRUCT || !n || *n != 1) {
        throw InputError(where(file, 0,
                               fmt::format("struct '{}' is not 1x1; jointlab reads one "
                                           "record per file",
                                           name)));
      }
      prefix = name + ".";
      const unsigned nf = Mat_VarGetNumberOfFields(var.get());
      char* const* fields = Mat_VarGetStructFieldnames(var.get());
      for (unsigned i = 0; fields && i < nf; ++i) {
        matvar_t* f = Mat_VarGetStructFieldByIndex(var.get(), i, 0);
        if (!fields[i] || !f || (mat_element_count(f).value_or(1) > 0 && !f->data)) {
          throw InputError(where(file, 0,
                                 fmt::format("field '{}.{}' could not be read (truncated "
                                             "or damaged file){}",
                                             name, fields[i] ? fields[i] : "?", matio_says())));
        }
        vars.push_back(Named{fields[i], f});
      }
    }
    owned.push_back(std::move(var));
  }
  Record rec = build_record(vars, file, prefix);
  rec.metadata["format"] = Mat_GetVersion(mat.get()) == MAT_FT_MAT73 ? "mat-v7.3" : "mat-v5";
  return rec;
}

// ---------------------------------------------------------------------------------------------
// Writer

namespace {

// A MATLAB identifier from a channel name: letters, digits, '_', starting with a letter.
std::string field_name(const std::string& name, const std::vector<std::string>& taken) {
  std::string s;
  for (char c : name) {
    s += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  }
  if (s.empty() || !std::isalpha(static_cast<unsigned char>(s[0]))) s = "ch_" + s;
  s = s.substr(0, 60);
  std::string out = s;
  for (int k = 2; std::find(taken.begin(), taken.end(), out) != taken.end(); ++k) {
    out = fmt::format("{}_{}", s, k);
  }
  return out;
}

matvar_t* double_column(const double* data, size_t n) {
  size_t dims[2] = {n, 1};
  return Mat_VarCreate(nullptr, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, const_cast<double*>(data), 0);
}

matvar_t* char_row(const std::string& text) {
  size_t dims[2] = {1, text.size()};
  return Mat_VarCreate(nullptr, MAT_C_CHAR, MAT_T_UTF8, 2, dims, const_cast<char*>(text.data()), 0);
}

std::atomic<unsigned> g_tmp_counter{0};

}  // namespace

void write_mat(const std::filesystem::path& path, const Record& record, MatVersion version) {
  const std::string file = path.string();
  check_writable(record, file);
  const auto n = static_cast<size_t>(record.size());
  quiet_matio();

  std::vector<std::string> fields = {"fs", "t0", "time"};
  for (const Channel& ch : record.channels) {
    std::vector<std::string> taken = fields;
    taken.push_back("units");
    taken.push_back("channel_names");
    fields.push_back(field_name(ch.name, taken));
  }
  fields.push_back("units");
  fields.push_back("channel_names");
  std::vector<const char*> field_ptrs;
  for (const auto& f : fields) field_ptrs.push_back(f.c_str());
  field_ptrs.push_back(nullptr);

  size_t one[2] = {1, 1};
  VarPtr st(Mat_VarCreateStruct2("record", 2, one, field_ptrs.data()));
  if (!st) throw InputError(where(file, 0, "cannot create the MATLAB struct" + matio_says()));
  std::vector<double> time(n);
  for (size_t k = 0; k < n; ++k) time[k] = record.t0 + static_cast<double>(k) / record.fs;
  Mat_VarSetStructFieldByName(st.get(), "fs", 0, double_column(&record.fs, 1));
  Mat_VarSetStructFieldByName(st.get(), "t0", 0, double_column(&record.t0, 1));
  Mat_VarSetStructFieldByName(st.get(), "time", 0, double_column(time.data(), n));
  std::string units = "s";
  size_t name_dims[2] = {record.channels.size(), 1};
  std::vector<matvar_t*> cells;
  for (size_t c = 0; c < record.channels.size(); ++c) {
    const Channel& ch = record.channels[c];
    Mat_VarSetStructFieldByName(st.get(), fields[3 + c].c_str(), 0,
                                double_column(ch.samples.data(), n));
    units += ", " + (ch.quantity ? si_unit(*ch.quantity) : std::string());
    cells.push_back(char_row(ch.name));
  }
  Mat_VarSetStructFieldByName(st.get(), "units", 0, char_row(units));
  Mat_VarSetStructFieldByName(
      st.get(), "channel_names", 0,
      Mat_VarCreate(nullptr, MAT_C_CELL, MAT_T_CELL, 2, name_dims, cells.data(), 0));

  const std::filesystem::path tmp =
      path.string() + fmt::format(".tmp-{}-{}", ::getpid(), g_tmp_counter++);
  const mat_ft ver = version == MatVersion::kV73 ? MAT_FT_MAT73 : MAT_FT_MAT5;
  bool ok = false;
  {
    MatPtr mat(Mat_CreateVer(tmp.c_str(), nullptr, ver));
    if (!mat) {
      std::filesystem::remove(tmp);
      throw InputError(where(file, 0,
                             version == MatVersion::kV73
                                 ? "cannot write MATLAB v7.3: matio here has no HDF5 "
                                   "support, or the file cannot be created" +
                                       matio_says()
                                 : "cannot create file" + matio_says()));
    }
    ok =
        Mat_VarWrite(mat.get(), st.get(),
                     version == MatVersion::kV5 ? MAT_COMPRESSION_ZLIB : MAT_COMPRESSION_NONE) == 0;
  }
  std::error_code ec;
  if (ok) std::filesystem::rename(tmp, path, ec);
  if (!ok || ec) {
    std::filesystem::remove(tmp, ec);
    throw InputError(where(file, 0, "cannot write the .mat file" + matio_says()));
  }
}

bool mat_v73_supported() {
  static const bool supported = [] {
    quiet_matio();
    const std::filesystem::path tmp = std::filesystem::temp_directory_path() /
                                      fmt::format("jointlab-v73-probe-{}.mat", ::getpid());
    mat_t* m = Mat_CreateVer(tmp.c_str(), nullptr, MAT_FT_MAT73);
    const bool ok = m != nullptr;
    if (m) Mat_Close(m);
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    return ok;
  }();
  return supported;
}

}  // namespace jointlab::data
