#include "jointlab/data/process_folder.h"

#include <cmath>
#include <cstdlib>
#include <optional>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/data/csv_lines.h"
#include "jointlab/data/json_reader.h"
#include "jointlab/data/output_stage.h"

namespace jointlab::data {
namespace {

namespace fs = std::filesystem;

// Typed access to summary.json with messages naming the file and the field path.
struct Fields {
  std::string file;
  [[noreturn]] void fail(const std::string& path, const std::string& what) const {
    throw InputError(fmt::format("{}: {}: {}", file, path, what));
  }
  const JsonValue& get(const JsonValue& obj, const std::string& path, const char* key,
                       JsonValue::Type type) const {
    const JsonValue* v = obj.find(key);
    if (!v) fail(path, fmt::format("missing \"{}\"", key));
    if (v->type() != type) {
      fail(path + "." + key, fmt::format("expected a {}, found a {}", JsonValue::type_name(type),
                                         JsonValue::type_name(v->type())));
    }
    return *v;
  }
  double number(const JsonValue& obj, const std::string& path, const char* key) const {
    return get(obj, path, key, JsonValue::Type::kNumber).number();
  }
  int band(const JsonValue& obj, const std::string& path) const {
    const double b = number(obj, path, "band");
    if (!(b >= 1) || b != std::floor(b) || b > 1e6) fail(path + ".band", "must be an integer >= 1");
    return static_cast<int>(b);
  }
};

Quantity quantity_of(const Fields& f, const std::string& name) {
  if (const std::optional<Quantity> q = parse_quantity(name); q && *q != Quantity::kForce)
    return *q;
  f.fail("amplitude_quantity",
         fmt::format("\"{}\" is not displacement, velocity or acceleration", name));
}

// The "program" that wrote a summary, or "" when it does not say.
std::string program_of(const JsonValue& doc) {
  const JsonValue* p = doc.find("program");
  return p && p->is_string() ? p->string() : std::string();
}

// The summary.json of the `program` output directory `dir`, checked to be an object.
JsonValue read_summary(const fs::path& dir, const std::string& program) {
  const fs::path path = dir / "summary.json";
  if (!fs::is_directory(dir)) {
    throw InputError(
        fmt::format("{}: not a directory (expected a '{}' output)", dir.string(), program));
  }
  if (!fs::exists(path)) {
    throw InputError(
        fmt::format("{}: missing (expected a '{}' output directory)", path.string(), program));
  }
  // A folder a killed commit left half old, half new is refused, never read as one run.
  data::require_complete_outputs(dir);
  JsonValue doc = data::read_json(path);
  if (!doc.is_object()) Fields{path.string()}.fail("document", "expected an object");
  return doc;
}

// The output file named by `key` of `obj`: a plain file name, or "" where it is null.
std::string output_file(const Fields& f, const JsonValue& obj, const std::string& path,
                        const char* key) {
  const JsonValue* v = obj.find(key);
  if (!v) f.fail(path, fmt::format("missing \"{}\"", key));
  if (v->is_null()) return {};
  if (!v->is_string()) f.fail(path + "." + key, "expected a string or null");
  const std::string& name = v->string();
  if (name.empty() || name.find('/') != std::string::npos)
    f.fail(path + "." + key, fmt::format("\"{}\" is not a file name", name));
  return name;
}

// The amplitude quantity the document's backbones are in. Their unit, when the document names
// one ("amplitude_unit", written by process and stepped-sine), must be that quantity's SI unit:
// the amplitudes are read as SI, so any other is refused, never ignored.
Quantity amplitude_of(const Fields& f, const JsonValue& doc) {
  const Quantity q = quantity_of(
      f, f.get(doc, "document", "amplitude_quantity", JsonValue::Type::kString).string());
  if (const JsonValue* unit = doc.find("amplitude_unit"); unit && !unit->is_null()) {
    const std::string si = si_unit(q);
    if (!unit->is_string() || unit->string() != si) {
      f.fail("amplitude_unit",
             fmt::format("{}: the backbones' amplitudes are read as SI ({} for {}); no other "
                         "unit is converted",
                         unit->is_string() ? "\"" + unit->string() + "\"" : "not a string", si,
                         doc.find("amplitude_quantity")->string()));
    }
  }
  return q;
}

// Calls on_file(file, path) for each entry of the document's "files" array, checked to be an
// object; path names it in messages ("files[i]").
template <typename OnFile>
void for_each_file(const Fields& f, const JsonValue& doc, OnFile on_file) {
  const JsonValue& files = f.get(doc, "document", "files", JsonValue::Type::kArray);
  for (size_t i = 0; i < files.items().size(); ++i) {
    const JsonValue& file = files.items()[i];
    const std::string fp = fmt::format("files[{}]", i);
    if (!file.is_object()) f.fail(fp, "expected an object");
    on_file(file, fp);
  }
}

// summary.json's coverage_factor: k of its *_std values (absent: 1, one sigma).
double coverage_factor_of(const Fields& f, const JsonValue& doc) {
  const JsonValue* k = doc.find("coverage_factor");
  if (!k || k->is_null()) return 1.0;
  if (!k->is_number() || !(k->number() >= 1) || !std::isfinite(k->number()))
    f.fail("coverage_factor", "not a finite number >= 1");
  return k->number();
}

}  // namespace

ProcessRun read_process_run(const fs::path& dir) {
  const JsonValue doc = read_summary(dir, "jointlab process");
  const Fields f{(dir / "summary.json").string()};
  if (program_of(doc) == "jointlab stepped-sine") {
    f.fail("program",
           "a 'jointlab stepped-sine' output, not a 'jointlab process' output (give "
           "it as stepped-sine data)");
  }
  ProcessRun run;
  run.dir = dir;
  run.amplitude = amplitude_of(f, doc);
  run.coverage_factor = coverage_factor_of(f, doc);
  for_each_file(f, doc, [&](const JsonValue& file, const std::string& fp) {
    const std::string source = f.get(file, fp, "file", JsonValue::Type::kString).string();
    const JsonValue& bands = f.get(file, fp, "bands", JsonValue::Type::kArray);
    for (size_t b = 0; b < bands.items().size(); ++b) {
      const JsonValue& band = bands.items()[b];
      const std::string bp = fmt::format("{}.bands[{}]", fp, b);
      if (!band.is_object()) f.fail(bp, "expected an object");
      ProcessBand pb;
      pb.source = source;
      pb.band = f.band(band, bp);
      pb.reference_channel =
          f.get(band, bp, "reference_channel", JsonValue::Type::kString).string();
      if (band.find("linear_frequency_hz")) {
        pb.linear_frequency_hz = f.number(band, bp, "linear_frequency_hz");
        if (!(pb.linear_frequency_hz > 0)) f.fail(bp + ".linear_frequency_hz", "must be > 0");
        // Optional: what says whether the files agree and how their level moves them.
        for (const auto& [key, value] :
             {std::pair{"linear_frequency_std_hz", &pb.linear_frequency_std_hz},
              std::pair{"linear_fit_amplitude_min", &pb.linear_fit_amplitude_min}}) {
          const JsonValue* v = band.find(key);
          if (!v || v->is_null()) continue;
          *value = f.number(band, bp, key);
          if (!(*value >= 0) || !std::isfinite(*value)) f.fail(bp + "." + key, "must be >= 0");
        }
      }
      const JsonValue& shape = f.get(band, bp, "operating_shape", JsonValue::Type::kArray);
      for (size_t c = 0; c < shape.items().size(); ++c) {
        const JsonValue& entry = shape.items()[c];
        const std::string cp = fmt::format("{}.operating_shape[{}]", bp, c);
        if (!entry.is_object()) f.fail(cp, "expected an object");
        pb.shape.emplace_back(
            f.get(entry, cp, "channel", JsonValue::Type::kString).string(),
            std::complex<double>(f.number(entry, cp, "real_m"), f.number(entry, cp, "imag_m")));
      }
      run.bands.push_back(std::move(pb));
    }
    const JsonValue& outputs = f.get(file, fp, "outputs", JsonValue::Type::kArray);
    for (size_t o = 0; o < outputs.items().size(); ++o) {
      const JsonValue& out = outputs.items()[o];
      const std::string op = fmt::format("{}.outputs[{}]", fp, o);
      if (!out.is_object()) f.fail(op, "expected an object");
      ProcessOutput po;
      po.source = source;
      po.channel = f.get(out, op, "channel", JsonValue::Type::kString).string();
      po.band = f.band(out, op);
      po.file = output_file(f, out, op, "file");
      run.outputs.push_back(std::move(po));
    }
  });
  return run;
}

SteppedSineRun read_stepped_sine_run(const fs::path& dir) {
  const JsonValue doc = read_summary(dir, "jointlab stepped-sine");
  const Fields f{(dir / "summary.json").string()};
  if (program_of(doc) != "jointlab stepped-sine") {
    f.fail("program",
           "not a 'jointlab stepped-sine' output (a 'jointlab process' output is "
           "given as ring-down data)");
  }
  SteppedSineRun run;
  run.dir = dir;
  run.amplitude = amplitude_of(f, doc);
  run.coverage_factor = coverage_factor_of(f, doc);
  for_each_file(f, doc, [&](const JsonValue& file, const std::string& fp) {
    SteppedSineOutput o;
    o.source = f.get(file, fp, "file", JsonValue::Type::kString).string();
    o.file = output_file(f, file, fp, "output");
    run.outputs.push_back(std::move(o));
  });
  return run;
}

BackboneTable read_process_backbone(const fs::path& path) {
  const std::string name = path.string();
  // amplitude, frequency_hz and damping_ratio are required; time_s and the two std columns read
  // where present (the std columns both or neither).
  const char* wanted[] = {"amplitude",        "frequency_hz", "damping_ratio",
                          "frequency_std_hz", "damping_std",  "time_s"};
  constexpr int kWanted = 6, kRequired = 3;
  int column[kWanted] = {-1, -1, -1, -1, -1, -1};
  std::vector<double> values[kWanted];
  std::vector<size_t> marks;  // columns of is_point_mark: their marked rows are skipped
  int coverage_col = -1;      // process's coverage_factor: k of the std columns
  double coverage = 0;        // its value (0: none read)
  const auto on_header = [&](const std::vector<std::string>& cells, long n) {
    for (size_t c = 0; c < cells.size(); ++c) {
      if (cells[c] == "coverage_factor") coverage_col = static_cast<int>(c);
      if (is_point_mark(cells[c])) marks.push_back(c);
      for (int k = 0; k < kWanted; ++k)
        if (cells[c] == wanted[k]) column[k] = static_cast<int>(c);
    }
    for (int k = 0; k < kRequired; ++k)
      if (column[k] < 0)
        throw InputError(where(name, n, fmt::format("no column '{}' in the header", wanted[k])));
    if ((column[3] < 0) != (column[4] < 0))
      throw InputError(where(
          name, n, fmt::format("no column '{}' in the header", wanted[column[3] < 0 ? 3 : 4])));
  };
  const auto on_row = [&](const std::vector<std::string>& cells, long n) {
    for (const size_t c : marks) {
      if (c < cells.size() && !cells[c].empty() && std::strtod(cells[c].c_str(), nullptr) != 0)
        return;
    }
    if (coverage_col >= 0 && static_cast<size_t>(coverage_col) < cells.size()) {
      const std::string& cell = cells[static_cast<size_t>(coverage_col)];
      coverage =
          coverage_factor_of_row(std::strtod(cell.c_str(), nullptr), coverage, cell, name, n);
    }
    for (int k = 0; k < kWanted; ++k) {
      if (column[k] < 0) continue;
      const std::string& cell = cells[static_cast<size_t>(column[k])];
      const std::optional<double> v = parse_double(cell);
      if (!v || !std::isfinite(*v)) {
        throw InputError(
            where(name, n, fmt::format("{} '{}' is not a finite number", wanted[k], cell)));
      }
      const double x = *v;
      if (k == 0 && !(x > 0)) throw InputError(where(name, n, "amplitude must be > 0"));
      if (k == 1 && !(x > 0)) throw InputError(where(name, n, "frequency_hz must be > 0"));
      if ((k == 3 || k == 4) && x < 0)
        throw InputError(where(name, n, fmt::format("{} must be >= 0", wanted[k])));
      values[k].push_back(x);
    }
  };
  if (!for_each_csv_row(path, "backbone file", on_header, on_row))
    throw InputError(where(name, 0, "empty file, expected a backbone header"));
  BackboneTable t;
  t.source = name;  // for messages, and which hit a curve is where several are returned
  auto vec = [&](int k) {
    if (column[k] < 0)
      return Eigen::VectorXd::Zero(static_cast<Eigen::Index>(values[0].size())).eval();
    return Eigen::Map<const Eigen::VectorXd>(values[k].data(),
                                             static_cast<Eigen::Index>(values[k].size()))
        .eval();
  };
  t.amplitude = vec(0);
  t.frequency_hz = vec(1);
  t.damping_ratio = vec(2);
  t.frequency_std_hz = vec(3);
  t.damping_std = vec(4);
  t.has_uncertainty = column[3] >= 0;
  if (column[5] >= 0) t.time_s = vec(5);
  if (coverage > 0) t.coverage_factor = coverage;
  t.written_by_jointlab = true;
  return t;
}

}  // namespace jointlab::data
