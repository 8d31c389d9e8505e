// The `jointlab` Python module: the library's process, stepped-sine, record reading, build-model,
// modes, QSMA, simulate, update-linear, update-iwan, compare and run with numpy arrays in and out
// (docs/python.md), the same options and defaults as the command line, and the command line's
// one-line messages as jointlab.InputError (a ValueError). Argument conversion only: every number
// comes from the library the program uses (style.md 13).
#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <regex>
#include <string>
#include <string_view>
#include <thread>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <glog/logging.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "jointlab/campaign/backbone_comparison.h"
#include "jointlab/campaign/campaign.h"
#include "jointlab/campaign/campaign_run.h"
#include "jointlab/campaign/iwan_fit.h"
#include "jointlab/campaign/iwan_inputs.h"
#include "jointlab/campaign/model_comparison.h"
#include "jointlab/campaign/steps/stamp.h"
#include "jointlab/core/error.h"
#include "jointlab/core/units.h"
#include "jointlab/correlate/iwan_update.h"
#include "jointlab/correlate/linear_update.h"
#include "jointlab/correlate/measured_data.h"
#include "jointlab/correlate/sensors.h"
#include "jointlab/correlate/update_files.h"
#include "jointlab/data/names.h"
#include "jointlab/data/output_stage.h"
#include "jointlab/data/read_record.h"
#include "jointlab/data/record_writer.h"
#include "jointlab/data/table_writer.h"
#include "jointlab/modal/process.h"
#include "jointlab/modal/process_output.h"
#include "jointlab/modal/stepped_sine.h"
#include "jointlab/modal/stepped_sine_output.h"
#include "jointlab/model/fe/model_builder.h"
#include "jointlab/model/fe/riveted_beam.h"
#include "jointlab/model/joint_condensation.h"
#include "jointlab/model/linear_modes.h"
#include "jointlab/model/model_file.h"
#include "jointlab/model/model_file_writer.h"
#include "jointlab/model/qsma.h"
#include "jointlab/model/qsma_output.h"
#include "jointlab/model/sim/ringdown_simulation.h"
#include "jointlab/model/sim/simulated_record.h"

namespace py = pybind11;

namespace jointlab::python {

/// The values of a repeatable option: a list (a tuple, a numpy array, any sequence) or one value
/// alone, as the option given once ("a.csv" as ["a.csv"], (70, 90) as [(70, 90)]); None as [],
/// the option not given.
template <typename T>
struct OneOrMany {
  std::vector<T> items;  ///< the values, in order
};

/// A Python integer of any size (an int or a numpy integer) where an integer option is taken:
/// its value where it fits, so that one beyond C's range (threads=10**10) is refused naming the
/// option and its range, not with pybind11's "incompatible function arguments" and the whole
/// signature.
struct Integer {
  std::string text;                                  ///< its decimal text
  std::optional<long long> value;                    ///< its value, where it fits a long long
  std::optional<unsigned long long> unsigned_value;  ///< its value, where it fits 64 bits >= 0
};

}  // namespace jointlab::python

namespace pybind11::detail {
// What pybind11's int caster takes (an int, a bool, anything with __index__; never a float),
// of any size.
template <>
struct type_caster<jointlab::python::Integer> {
  PYBIND11_TYPE_CASTER(jointlab::python::Integer, const_name("int"));
  bool load(handle src, bool) {
    if (PyFloat_Check(src.ptr()) != 0 || PyIndex_Check(src.ptr()) == 0) return false;
    const object index = reinterpret_steal<object>(PyNumber_Index(src.ptr()));
    if (!index) {
      PyErr_Clear();
      return false;
    }
    value.text = str(index).cast<std::string>();
    int overflow = 0;
    const long long v = PyLong_AsLongLongAndOverflow(index.ptr(), &overflow);
    value.value.reset();
    value.unsigned_value.reset();
    if (overflow == 0) {
      value.value = v;
      if (v >= 0) value.unsigned_value = static_cast<unsigned long long>(v);
    } else if (overflow > 0) {
      const unsigned long long u = PyLong_AsUnsignedLongLong(index.ptr());
      if (PyErr_Occurred() != nullptr)
        PyErr_Clear();
      else
        value.unsigned_value = u;
    }
    return true;
  }
  static handle cast(const jointlab::python::Integer& v, return_value_policy, handle) {
    return PyLong_FromString(v.text.c_str(), nullptr, 10);
  }
};

// One value is tried first: a str, a path or a (lo, hi) pair never loads as a list of them, so a
// list is never read as one value (a str was refused with pybind11's "incompatible function
// arguments" and the whole signature).
template <typename T>
struct type_caster<jointlab::python::OneOrMany<T>> {
  PYBIND11_TYPE_CASTER(jointlab::python::OneOrMany<T>, const_name("Union[") + make_caster<T>::name +
                                                           const_name(", List[") +
                                                           make_caster<T>::name + const_name("]]"));
  bool load(handle src, bool convert) {
    // None: not given (channels=None in update_iwan was a TypeError, where process takes it).
    if (src.is_none()) {
      value.items.clear();
      return true;
    }
    if (make_caster<T> one; one.load(src, convert)) {
      value.items.clear();
      value.items.push_back(cast_op<T&&>(std::move(one)));
      return true;
    }
    make_caster<std::vector<T>> many;
    if (!many.load(src, convert)) {
      if constexpr (std::is_same_v<T, std::filesystem::path>) refuse_backbones(src);
      return false;
    }
    value.items = cast_op<std::vector<T>&&>(std::move(many));
    return true;
  }
  // process()'s Backbones where files are asked for (update_iwan's or compare's backbones=):
  // said with the way to pass them, not as pybind11's "incompatible function arguments".
  static void refuse_backbones(handle src) {
    const auto backbone = [](handle h) {
      return std::string_view(Py_TYPE(h.ptr())->tp_name) == "jointlab.Backbone";
    };
    bool any = backbone(src);
    if (!any && (PyList_Check(src.ptr()) != 0 || PyTuple_Check(src.ptr()) != 0))
      for (const handle h : reinterpret_borrow<sequence>(src)) any = any || backbone(h);
    if (any)
      throw jointlab::InputError(
          "a jointlab.Backbone where a file is expected: update_iwan and compare read process()'s "
          "backbones from the folder process(..., out=DIR) writes (measured=DIR with "
          "sensors=FILE); backbones= takes backbone tables (CSV files)");
  }
  static handle cast(const jointlab::python::OneOrMany<T>& v, return_value_policy policy,
                     handle parent) {
    return make_caster<std::vector<T>>::cast(v.items, policy, parent);
  }
};
}  // namespace pybind11::detail

namespace jointlab::python {
namespace {

// A numpy array over the vector's own storage: the vector moves into a capsule that numpy
// frees with the array, so nothing is copied.
py::array_t<double> to_numpy(Eigen::VectorXd v) {
  auto* owned = new Eigen::VectorXd(std::move(v));
  py::capsule free(owned, [](void* p) { delete static_cast<Eigen::VectorXd*>(p); });
  return py::array_t<double>(owned->size(), owned->data(), free);
}

// A matrix as a 2-D numpy array over its own storage (column-major, as Eigen keeps it), nothing
// copied.
py::array_t<double> to_numpy(Eigen::MatrixXd m) {
  auto* owned = new Eigen::MatrixXd(std::move(m));
  py::capsule free(owned, [](void* p) { delete static_cast<Eigen::MatrixXd*>(p); });
  const auto size = static_cast<py::ssize_t>(sizeof(double));
  return py::array_t<double>({owned->rows(), owned->cols()}, {size, size * owned->rows()},
                             owned->data(), free);
}

// A table's columns as a dict of numpy arrays, named as the CSV's header.
py::dict to_dict(data::Table table) {
  py::dict out;
  for (size_t i = 0; i < table.names.size(); ++i)
    out[py::str(table.names[i])] = to_numpy(std::move(table.columns[i]));
  return out;
}

// A file or folder argument: a str or any os.PathLike (pathlib.Path), as open() takes them.
using PathArg = std::filesystem::path;
std::string text(const PathArg& p) { return p.string(); }
std::optional<std::string> text(const std::optional<PathArg>& p) {
  return p ? std::optional<std::string>(p->string()) : std::nullopt;
}
std::vector<std::string> text(const std::vector<PathArg>& v) {
  std::vector<std::string> out;
  for (const PathArg& p : v) out.push_back(p.string());
  return out;
}

// An integer as a mode number: a Python int or a numpy integer (np.arange's, say), not a bool.
bool is_integer(const py::handle& h) {
  return !py::isinstance<py::bool_>(h) && PyIndex_Check(h.ptr()) != 0;
}

// An integer's decimal text, however large (10**30 raised a RuntimeError, "Unable to cast", as
// a long long): the command's reader then says what is wrong with it.
std::string integer_text(const py::handle& h) {
  return py::str(py::int_(py::reinterpret_borrow<py::object>(h))).cast<std::string>();
}

// An integer option in [lo, hi]; InputError "OPTION V: must be in [LO, HI]NOTE" otherwise, as the
// command says it.
long long in_range(const Integer& v, std::string_view option, long long lo, long long hi,
                   std::string_view note = "") {
  if (!v.value || *v.value < lo || *v.value > hi)
    throw InputError(fmt::format("{} {}: must be in [{}, {}]{}", option, v.text, lo, hi, note));
  return *v.value;
}

// An integer option as an int where the library (or a check below) says what is wrong with a
// value in C's range: beyond it, InputError with the range [lo, INT_MAX].
int as_int(const Integer& v, std::string_view option, int lo) {
  using limits = std::numeric_limits<int>;
  if (v.value && *v.value >= limits::min() && *v.value <= limits::max())
    return static_cast<int>(*v.value);
  throw InputError(fmt::format("{} {}: must be in [{}, {}]", option, v.text, lo, limits::max()));
}

// --threads, as the commands take it.
unsigned threads_option(const Integer& v) {
  return static_cast<unsigned>(in_range(v, "--threads", 0, 1024, " (0: every core)"));
}

// The model file `path` (its matrices beside it), its folder created if missing as the commands
// create their --out folders (a missing one was refused after the fit, naming a temporary file).
void write_model(const std::string& path, const model::Model& m) {
  const std::filesystem::path file(path);
  std::error_code ec;
  if (!file.parent_path().empty()) std::filesystem::create_directories(file.parent_path(), ec);
  if (ec)
    throw InputError(
        fmt::format("{}: cannot create the output directory", file.parent_path().string()));
  model::write_model_file(file, m);
}

// "acceleration", "velocity" or "displacement", as --quantity and --amplitude take them.
// Progress to a Python callable (or nowhere): the GIL is taken for the call only, and a pending
// Ctrl-C ends the work with KeyboardInterrupt.
void report(const py::object& progress, const std::string& line) {
  py::gil_scoped_acquire gil;
  if (PyErr_CheckSignals() != 0) throw py::error_already_set();
  if (!progress.is_none()) progress(line);
}

// `progress` is None or a callable, said before any work (progress=5 raised "'int' object is not
// callable" a file or an iteration in, naming no argument).
void check_progress(const py::object& progress) {
  if (!progress.is_none() && PyCallable_Check(progress.ptr()) == 0)
    throw py::type_error(
        fmt::format("progress: expected a callable taking one line of text, or None; got {}",
                    Py_TYPE(progress.ptr())->tp_name));
}

// A Ctrl-C seen on the calling thread, carried to the worker threads of the same call.
struct Interrupted {};

// A pending Ctrl-C ends the work with KeyboardInterrupt; checked at most every 0.1 s, so that a
// check at each of many short steps (QSMA evaluations, model solves) costs no GIL round trip
// each. Work may call it from worker threads too (update_linear's sweeps): Python takes signals
// on its main thread only, so the calling thread checks and the others stop at their next call
// once it has seen one; an Interrupted that reaches Python is KeyboardInterrupt (registered in
// the module).
class InterruptCheck {
 public:
  void operator()() {
    if (stopped_.load()) throw Interrupted{};
    if (std::this_thread::get_id() != caller_) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) {
      stopped_.store(true);
      throw py::error_already_set();
    }
  }

 private:
  const std::thread::id caller_ = std::this_thread::get_id();
  std::chrono::steady_clock::time_point last_{};  // the caller's thread alone reads and sets it
  std::atomic<bool> stopped_{false};
};

/// One backbone of process(): its identity, linear values and columns (set as attributes).
struct Backbone {
  std::string file;     // the record processed
  std::string channel;  // its channel
  int band = 0;         // 1-based band
  // The linear values: none where the band has none (linear_reason says why), as summary.json
  std::optional<double> linear_frequency_hz;       // natural frequency at low amplitude [Hz]
  std::optional<double> linear_damping_ratio;      // damping ratio at low amplitude
  std::optional<double> linear_frequency_std_hz;   // its expanded uncertainty (k sigma) [Hz]
  std::optional<double> linear_damping_std;        // its expanded uncertainty (k sigma)
  std::complex<double> complex_amplitude;          // operating-shape entry [m]
  std::string report;                              // the summary paragraph of the band
  bool reference = false;                          // the band's reference channel in its file
  std::string amplitude_quantity;                  // what .amplitude measures ("velocity", ...)
  std::string amplitude_unit;                      // its SI unit ("m/s")
  std::optional<double> linear_fit_amplitude_min;  // lowest amplitude of that fit [SI]
  std::optional<double> linear_fit_amplitude_max;  // highest amplitude of that fit [SI]
  std::string linear_reason;                       // why there are no linear values ("")
  double noise_floor_m = 0;                        // noise floor of the displacement envelope [m]
};

// Names of the files `jointlab process` writes: summary.json and "<stem>.<channel>.band<k>.csv"
// (apps/process_command.cc), replaced as a set in a folder an older run wrote.
bool is_process_output(const std::string& name) {
  static const std::regex backbone(R"(.*\.band[0-9]+\.csv)");
  return name == "summary.json" || std::regex_match(name, backbone);
}

py::list process(const OneOrMany<PathArg>& file_args,
                 const std::optional<OneOrMany<std::pair<double, double>>>& bands,
                 const Integer& modes_arg, const std::optional<OneOrMany<std::string>>& channels,
                 const std::optional<std::string>& quantity, const std::string& amplitude,
                 const py::object& progress, const Integer& threads, const std::string& method,
                 double snr_min, double max_damping_std, double coverage_factor, double min_share,
                 const std::optional<PathArg>& out_arg) {
  check_progress(progress);
  const std::vector<std::string> files = text(file_args.items);
  const std::optional<std::string> out = text(out_arg);
  modal::ProcessOptions opt;
  opt.threads = threads_option(threads);
  const int modes = as_int(modes_arg, "--modes", 0);
  if (bands && !bands->items.empty() && modes != 0)  // bands=[] is none, as None
    throw InputError("process: give bands or modes=N, not both (--band excludes --modes)");
  // --method, --snr-min, --max-damping-std, --coverage-factor and --min-share, in the command's
  // ranges.
  if (method != "hilbert" && method != "pff")
    throw InputError(fmt::format("--method {}: expected hilbert or pff", method));
  opt.ringdown.method = method == "pff" ? modal::Method::kPeaks : modal::Method::kHilbert;
  for (const auto& [name, value, lo, hi] :
       {std::tuple{"--snr-min", snr_min, 1.0, 1e6},
        std::tuple{"--max-damping-std", max_damping_std, 1e-6, 10.0},
        std::tuple{"--coverage-factor", coverage_factor, 1.0, 10.0},
        std::tuple{"--min-share", min_share, 0.0, 0.99}}) {
    if (!(value >= lo && value <= hi))
      throw InputError(fmt::format("{} {}: must be in [{:g}, {:g}]", name, value, lo, hi));
  }
  opt.ringdown.snr_min = snr_min;
  opt.ringdown.max_damping_rel_std = max_damping_std;
  opt.ringdown.coverage_factor = coverage_factor;
  opt.min_share = min_share;
  if (bands) {
    for (const auto& [lo, hi] : bands->items) {
      if (!(std::isfinite(lo) && std::isfinite(hi) && lo > 0 && hi > lo))
        throw InputError(fmt::format("--band {:g}:{:g}: need 0 < LO < HI (Hz)", lo, hi));
      opt.bands.push_back({lo, hi});
    }
  }
  opt.modes = modes;
  if (channels && channels->items.empty())
    throw InputError("process: channels=[] names no channel (None: every non-force channel)");
  if (channels) opt.channels = channels->items;
  if (quantity) opt.quantity = motion_quantity("--quantity", *quantity);
  opt.ringdown.amplitude = motion_quantity("--amplitude", amplitude);
  if (std::string why = opt.check(); !why.empty()) throw InputError(why);
  if (files.empty()) throw InputError("process: no file given");
  if (out) data::check_distinct_stems(files);
  std::vector<modal::RecordResult> results;
  {
    py::gil_scoped_release release;
    // `out`: the folder `jointlab process --out` writes (the backbone CSVs and summary.json that
    // update_linear's and update_iwan's `measured` read), replacing a previous run's as a set.
    std::optional<data::OutputStage> stage;
    if (out) {
      const bool old = std::filesystem::exists(std::filesystem::path(*out) / "summary.json");
      stage.emplace(*out, "process",
                    old ? std::function<bool(const std::string&)>(is_process_output)
                        : std::function<bool(const std::string&)>{});
    }
    signal::FftCache cache;
    for (const std::string& f : files) {
      report(progress, fmt::format("process: {}", f));
      const data::Record rec = data::read_record(f);
      results.push_back(modal::process_record(rec, opt, cache));
      if (stage) modal::write_backbones(stage->path(), results.back(), opt.ringdown);
      // The command's stderr line for each channel and band: the span kept, or why none was
      // (a channel near a node, no span above the noise), which no Backbone carries.
      if (!progress.is_none()) {
        for (const modal::ChannelBand& c : results.back().results)
          report(progress, fmt::format("{} {} band {}: {}", f, c.channel, c.band_index,
                                       c.ringdown.summary.report()));
      }
    }
    if (stage) {
      modal::write_summary(stage->path(), results, opt);
      stage->commit();
    }
  }
  py::list backbones;
  for (const modal::RecordResult& r : results) {
    for (const modal::ChannelBand& c : r.results) {
      if (c.ringdown.summary.status != modal::RingdownStatus::kOk) continue;
      const modal::RingdownSummary& s = c.ringdown.summary;
      // No linear values (every point superharmonic, say): None, not 0 (summary.json writes
      // none, with linear_reason; 0 Hz was returned).
      const auto linear = [&s](double v) {
        return s.has_linear() ? std::optional<double>(v) : std::nullopt;
      };
      Backbone bb;
      bb.file = r.source;
      bb.channel = c.channel;
      bb.band = c.band_index;
      bb.linear_frequency_hz = linear(s.linear_frequency_hz);
      bb.linear_damping_ratio = linear(s.linear_damping);
      bb.linear_frequency_std_hz = linear(s.linear_frequency_std_hz);
      bb.linear_damping_std = linear(s.linear_damping_std);
      bb.complex_amplitude = c.complex_amplitude;
      bb.report = s.report();
      // As summary.json's reference_channel: the curve update_iwan and compare read by default.
      const auto k = static_cast<size_t>(c.band_index - 1);
      bb.reference = k < r.reference.size() && r.reference[k] == c.channel;
      // As summary.json: the amplitude's quantity and unit, the span of the linear values' fit
      // (the level a hit's linear frequency was read at) and the noise floor.
      bb.amplitude_quantity = quantity_name(opt.ringdown.amplitude);
      bb.amplitude_unit = si_unit(opt.ringdown.amplitude);
      bb.linear_fit_amplitude_min = linear(s.linear_fit_min);
      bb.linear_fit_amplitude_max = linear(s.linear_fit_max);
      bb.linear_reason = s.linear_reason;
      bb.noise_floor_m = s.noise_floor_m;
      py::object b = py::cast(std::move(bb));
      py::dict columns = to_dict(modal::backbone_table(c.ringdown.backbone, opt.ringdown));
      for (auto item : columns) b.attr(item.first) = item.second;
      backbones.append(b);
    }
  }
  if (backbones.empty()) {
    std::string why;
    for (const modal::RecordResult& r : results)
      for (size_t k = 0; k < r.bands.size() && why.empty(); ++k)
        why = modal::band_without_backbone(r, static_cast<int>(k) + 1);
    throw InputError(fmt::format("process: no backbone at any channel, band or file; {}", why));
  }
  // What the command writes and then fails with (exit 2) is returned here with a warning: fewer
  // modes than modes=N asked for, or a band without a backbone in some file. Each peak modes=N
  // left out goes to `progress`, as the command writes it to stderr.
  for (const modal::RecordResult& r : results) {
    for (const modal::LeftOutPeak& p : r.left_out) {
      report(progress, fmt::format("process: {}: {}", r.source, modal::left_out_line(p)));
    }
    std::vector<std::string> why;
    if (!r.shortfall.empty()) why.push_back(r.shortfall);
    for (size_t k = 0; k < r.bands.size(); ++k) {
      if (std::string w = modal::band_without_backbone(r, static_cast<int>(k) + 1); !w.empty())
        why.push_back(fmt::format("band {} ({:g}:{:g} Hz): no backbone at any channel; {}", k + 1,
                                  r.bands[k].lo, r.bands[k].hi, w));
    }
    // A band whose reference channel has a backbone but no linear values, as the command fails
    // on it (update_linear reads no frequency for the band from this file).
    for (const modal::ChannelBand& c : r.results) {
      const auto k = static_cast<size_t>(c.band_index - 1);
      const modal::RingdownSummary& s = c.ringdown.summary;
      if (k < r.bands.size() && k < r.reference.size() && c.channel == r.reference[k] &&
          s.status == modal::RingdownStatus::kOk && !s.has_linear())
        why.push_back(fmt::format("band {} ({:g}:{:g} Hz): {}: {}", k + 1, r.bands[k].lo,
                                  r.bands[k].hi, c.channel, s.linear_reason));
    }
    for (const std::string& w : why) {
      const std::string message = fmt::format("process: {}: {}", r.source, w);
      if (PyErr_WarnEx(PyExc_UserWarning, message.c_str(), 1) != 0) throw py::error_already_set();
    }
  }
  return backbones;
}

// A record as read_record() and simulate() return it: its channels as numpy arrays (SI).
py::dict record_dict(data::Record rec) {
  py::dict out;
  out["source"] = rec.source;
  out["sample_rate_hz"] = rec.fs;
  out["t0_s"] = rec.t0;
  // The samples' times t0 + i / fs, as the library dates them: the x axis of a plot of `data`.
  Eigen::VectorXd time(rec.size());
  for (Eigen::Index i = 0; i < time.size(); ++i) time(i) = rec.t0 + static_cast<double>(i) / rec.fs;
  out["time_s"] = to_numpy(std::move(time));
  py::list names, units, quantities;
  py::dict data;
  for (data::Channel& c : rec.channels) {
    names.append(c.name);
    units.append(c.unit);
    quantities.append(c.quantity ? py::object(py::str(quantity_name(*c.quantity))) : py::none());
    data[py::str(c.name)] = to_numpy(std::move(c.samples));
  }
  out["channels"] = names;
  out["units"] = units;
  out["quantities"] = quantities;
  out["data"] = data;
  out["metadata"] = rec.metadata;
  return out;
}

py::dict read_record(const PathArg& path_arg) {
  const std::string path = text(path_arg);
  data::Record rec;
  {
    py::gil_scoped_release release;
    rec = data::read_record(path);
  }
  return record_dict(std::move(rec));
}

/// A model file, read once.
class Model {
 public:
  explicit Model(const PathArg& path) : path_(text(path)), model_(model::read_model(path_)) {}
  const std::string& path() const { return path_; }
  /// The model as the library reads it.
  const model::Model& model() const { return model_; }
  /// The damping ratio of every elastic mode ([damping] modal_ratio; 0 without one).
  double modal_ratio() const { return model_.modal_ratio; }

  /// "node:component" per matrix index (the model's dof_labels), or empty.
  const std::vector<std::string>& dof_labels() const { return model_.dof_labels; }
  /// Number of matrix DOFs.
  Eigen::Index dofs() const { return model_.size(); }
  /// What the model is, in a line: its file, DOFs and joints.
  std::string repr() const {
    return fmt::format("<jointlab.Model {}: {} DOFs, {} joint elements ({} Iwan)>", path_,
                       model_.size(), model_.joints.size(), model_.iwan_count());
  }

  py::array_t<double> modes(const Integer& count) const {
    const model::LinearModes modes = solve(count);
    Eigen::VectorXd f(modes.size() - modes.rigid_count);
    for (Eigen::Index i = 0; i < f.size(); ++i)
      f(i) = modes.frequency_hz(modes.rigid_count + static_cast<int>(i));
    return to_numpy(std::move(f));
  }

  // The elastic shapes of modes(count), mass-normalised, a column per mode.
  py::array_t<double> shapes(const Integer& count) const {
    const model::LinearModes modes = solve(count);
    return to_numpy(Eigen::MatrixXd(modes.shapes.rightCols(modes.size() - modes.rigid_count)));
  }

  py::dict qsma(const Integer& mode_arg, const Integer& points, std::optional<double> qmin,
                std::optional<double> qmax) const {
    model::QsmaOptions options;
    options.points = static_cast<int>(in_range(points, "--points", 2, 100000));
    const int mode = as_int(mode_arg, "--mode", 1);
    options.q_min = qmin.value_or(0.0);
    options.q_max = qmax.value_or(0.0);
    if (mode < 1) throw InputError(fmt::format("--mode {}: elastic modes count from 1", mode));
    if ((qmin && !(*qmin > 0)) || (qmax && !(*qmax > 0)))
      throw InputError("qsma: qmin and qmax must be > 0");
    if (const std::string e = options.error(); !e.empty())
      throw InputError(fmt::format("qsma: {}", e));
    if (model_.iwan_count() == 0)
      throw InputError(where(path_, 0, "the model has no Iwan joint; QSMA needs one"));
    std::vector<model::QsmaPoint> curve;
    model::QsmaSummary summary;
    {
      py::gil_scoped_release release;
      model::ModesOptions modes;
      modes.elastic_count = mode;
      const model::JointCondensation condensed(model_, modes);
      curve = model::qsma(condensed, mode, options, &summary);
    }
    if (curve.empty()) throw InputError(fmt::format("qsma: {}", summary.message));
    py::dict out = to_dict(model::qsma_table(curve));
    out["message"] = summary.message;
    return out;
  }

 private:
  // The lowest `count` modes, as `jointlab modes --count` solves them.
  model::LinearModes solve(const Integer& count_arg) const {
    const int count = as_int(count_arg, "--count", 1);
    if (count < 1) throw InputError(fmt::format("--count {}: must be >= 1", count));
    model::ModesOptions options;
    options.count = count;
    py::gil_scoped_release release;
    return model::linear_modes(model_, options);
  }

  std::string path_;
  model::Model model_;
};

// The status of update_linear() as a word for Python.
std::string linear_status_name(correlate::LinearUpdateStatus status) {
  switch (status) {
    case correlate::LinearUpdateStatus::kConverged:
      return "converged";
    case correlate::LinearUpdateStatus::kIterationLimit:
      return "iteration_limit";
    case correlate::LinearUpdateStatus::kTooFewPairs:
      return "too_few_pairs";
    case correlate::LinearUpdateStatus::kFailed:
      return "failed";
    case correlate::LinearUpdateStatus::kAmbiguous:
      return "ambiguous";
    case correlate::LinearUpdateStatus::kShapesRefused:
      return "shapes_refused";
    case correlate::LinearUpdateStatus::kPairsUnconfirmed:
      return "pairs_unconfirmed";
  }
  return "failed";
}

// --hold NAME[=VALUE], read as the command reads it: the whole VALUE a finite stiffness > 0
// ("1e7xyz" was held at 1e7).
correlate::ParameterHold hold_option(const std::string& h) {
  const size_t eq = h.rfind('=');
  correlate::ParameterHold ph{h.substr(0, eq), 0};
  if (eq != std::string::npos) {
    const std::string text = h.substr(eq + 1);
    char* end = nullptr;
    ph.value = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size() || std::isspace(text.front()) != 0 ||
        !std::isfinite(ph.value))
      throw InputError(fmt::format("--hold {}: {} is not a finite number", h, text));
    if (!(ph.value > 0))
      throw InputError(fmt::format("--hold {}: the value must be a stiffness > 0", h));
  }
  if (ph.name.empty()) throw InputError(fmt::format("--hold {}: expected NAME[=VALUE]", h));
  return ph;
}

// update_linear()'s keywords as the command's options name them.
struct LinearArgs {
  std::string rule;                                         // --rule
  std::optional<std::string> minimize;                      // --minimize
  double tolerance = 0;                                     // --tolerance
  double frequency_window = 0;                              // --frequency-window
  double mac_threshold = 0;                                 // --mac-threshold
  double frequency_std = 0;                                 // --frequency-std
  std::vector<std::string> hold;                            // --hold NAME[=VALUE]
  bool trust_signs = false;                                 // --trust-signs
  std::map<std::string, std::pair<double, double>> bounds;  // --bound NAME=LO:HI
  std::optional<std::pair<double, double>> bound_factors;   // --bound-factors LO:HI
  double alias_mac = 0;                                     // --alias-mac
};

// The options of the update, checked as the command checks them (progress and interrupt are
// the caller's).
correlate::LinearUpdateOptions linear_options(const LinearArgs& a) {
  correlate::LinearUpdateOptions o;
  o.alias_mac = a.alias_mac;
  // --bound NAME=LO:HI and --bound-factors LO:HI, checked as the command checks them.
  for (const auto& [name, range] : a.bounds) {
    const auto [lo, hi] = range;
    if (!(std::isfinite(lo) && std::isfinite(hi) && lo > 0 && lo < hi))
      throw InputError(
          fmt::format("--bound {}={}:{}: need 0 < LO < HI (stiffness values)", name, lo, hi));
    o.bounds.push_back({name, lo, hi});
  }
  if (a.bound_factors) {
    const auto [lo, hi] = *a.bound_factors;
    if (!(lo > 0 && lo < 1 && hi > 1 && std::isfinite(hi)))
      throw InputError(fmt::format("--bound-factors {}:{}: need 0 < LO < 1 < HI", lo, hi));
    o.lower_factor = lo;
    o.upper_factor = hi;
  }
  o.trust_signs = a.trust_signs;
  o.frequency_window = a.frequency_window;
  o.mac_threshold = a.mac_threshold;
  o.frequency_std = a.frequency_std;
  o.tolerance = a.tolerance;
  if (a.rule == "smallest") {
    o.rule = correlate::LinearRule::kSmallest;
    if (!a.minimize) throw InputError("update-linear: --rule smallest needs --minimize NAME");
    o.smallest_set = *a.minimize;
    if (!(o.tolerance > 0)) o.tolerance = 0.01;  // the paper's 1 %, as the command
  } else if (a.rule != "least-squares") {
    throw InputError(fmt::format("--rule {}: expected least-squares or smallest", a.rule));
  }
  for (const std::string& h : a.hold) o.holds.push_back(hold_option(h));
  if (const std::string e = o.error(); !e.empty())
    throw InputError(fmt::format("update-linear: {}", e));
  return o;
}

// One set's entry of 'parameters': its report's values, and its one-at-a-time sweep around the
// result as sweeps.csv's rows of the set: NaN where no pair is followed (rms_error) or the mode
// is unpaired or not followed by its shape (errors, a row per point, a column per measured mode
// in `modes` order).
py::dict linear_parameter(const correlate::ParameterReport& p, Eigen::Index measured_count) {
  py::dict d;
  d["initial"] = p.start;
  d["final"] = p.value;
  d["relative_std"] = p.relative_std ? py::object(py::float_(*p.relative_std)) : py::none();
  // Where relative_std is a third of the chi-square profile's 3-sigma distance (wider): the
  // local slope's, which the report names as understating it (None: relative_std is it).
  d["slope_std"] = p.slope_std ? py::object(py::float_(*p.slope_std)) : py::none();
  d["sensitivity"] = p.sensitivity;
  d["flat"] = p.flat;
  d["held"] = p.held;
  d["held_by_user"] = p.held_by_user;  // held by `hold`, not for being flat
  d["at_bound"] = p.at_bound;
  // As parameters.csv's identifiable: neither flat nor acting together with another set.
  d["identifiable"] = p.identifiable();
  d["acts_with"] = p.acts_with;
  // +1 / -1: the frequencies bound it from below / above only (not identifiable either).
  d["one_sided"] = p.one_sided;
  // As parameters.csv's column: the smallest value within the tolerance (None: not lowered).
  d["smallest_within_tolerance"] = p.smallest_within_tolerance > 0
                                       ? py::object(py::float_(p.smallest_within_tolerance))
                                       : py::object(py::none());
  d["lower"] = p.lower;  // its bounds [N/m or N m/rad]
  d["upper"] = p.upper;
  const auto n = static_cast<Eigen::Index>(p.sweep_factor.size());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Eigen::VectorXd factor(n), rms(n);
  Eigen::MatrixXd errors = Eigen::MatrixXd::Constant(n, measured_count, nan);
  for (Eigen::Index k = 0; k < n; ++k) {
    const auto kk = static_cast<size_t>(k);
    factor(k) = p.sweep_factor[kk];
    rms(k) = p.sweep_rms[kk].value_or(nan);
    for (Eigen::Index i = 0; i < measured_count; ++i) {
      const auto c = static_cast<size_t>(i);
      if (kk < p.sweep_errors.size() && c < p.sweep_errors[kk].size() && p.sweep_errors[kk][c])
        errors(k, i) = *p.sweep_errors[kk][c];
    }
  }
  py::dict sweep;
  sweep["factor"] = to_numpy(Eigen::VectorXd(factor));
  sweep["stiffness"] = to_numpy(Eigen::VectorXd(factor * p.value));
  sweep["rms_error"] = to_numpy(std::move(rms));
  sweep["errors"] = to_numpy(std::move(errors));
  d["sweep"] = sweep;
  return d;
}

// The objective and every set's stiffness after each iteration (the first: the start), as
// history.csv's columns.
py::dict linear_history(const correlate::LinearUpdateSummary& s) {
  py::dict history;
  const auto n = static_cast<Eigen::Index>(s.history.size());
  Eigen::VectorXd iteration(n), objective(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    iteration(i) = static_cast<double>(i);
    objective(i) = s.history[static_cast<size_t>(i)];
  }
  history["iteration"] = to_numpy(std::move(iteration));
  history["objective"] = to_numpy(std::move(objective));
  for (size_t k = 0; k < s.parameters.size(); ++k) {
    Eigen::VectorXd theta = Eigen::VectorXd::Constant(n, std::numeric_limits<double>::quiet_NaN());
    for (Eigen::Index i = 0; i < n && static_cast<size_t>(i) < s.theta_history.size(); ++i)
      if (static_cast<Eigen::Index>(k) < s.theta_history[static_cast<size_t>(i)].size())
        theta(i) = s.theta_history[static_cast<size_t>(i)](static_cast<Eigen::Index>(k));
    history[py::str(s.parameters[k].name)] = to_numpy(std::move(theta));
  }
  return history;
}

// Sets acting together, as the report's warning names them: the combination determined.
py::list linear_collinear(const correlate::LinearUpdateSummary& s) {
  py::list collinear;
  for (const correlate::CollinearSets& c : s.collinear) {
    py::dict d;
    std::vector<std::string> names;
    for (const int k : c.sets) names.push_back(s.parameters[static_cast<size_t>(k)].name);
    d["sets"] = names;
    d["determined"] = c.determined;
    d["correlation"] = c.correlation;
    const bool pair = c.sets.size() == 2;
    d["weight"] = pair ? py::object(py::float_(c.weight)) : py::object(py::none());
    d["value"] = pair ? py::object(py::float_(c.value)) : py::object(py::none());
    d["relative_std"] =
        pair && c.relative_std ? py::object(py::float_(*c.relative_std)) : py::object(py::none());
    collinear.append(d);
  }
  return collinear;
}

// The measured modes and their pairs at the result, as modes.csv; `spread`: per measured mode
// (by its id), the relative std its files' spread shows (> 0 only).
py::list linear_pairs(const correlate::LinearEvaluation& e,
                      const std::map<std::string, double>& spread) {
  py::list modes;
  for (Eigen::Index i = 0; i < e.measured_frequency_hz.size(); ++i) {
    const int j = e.pairing.model_for(static_cast<int>(i));
    py::dict d;
    // Its own number (the table's mode column, the band), as modes.csv writes it.
    const std::string id = e.measured_id(i);
    const bool number =
        !id.empty() && id.size() < 10 &&
        std::all_of(id.begin(), id.end(), [](char ch) { return ch >= '0' && ch <= '9'; });
    d["measured"] = number ? py::object(py::int_(std::stoi(id))) : py::object(py::str(id));
    d["frequency_hz"] = e.measured_frequency_hz(i);
    d["model_mode"] = j < 0 ? py::object(py::none()) : py::object(py::int_(j + 1));
    d["model_frequency_hz"] =
        j < 0 ? py::object(py::none()) : py::object(py::float_(e.model_frequency_hz(i)));
    d["error"] = j < 0 ? py::object(py::none()) : py::object(py::float_(e.residuals(i)));
    const std::optional<double> mac = e.pair_mac(i);
    d["mac"] = mac ? py::object(py::float_(*mac)) : py::object(py::none());
    // The relative one-sigma uncertainty of its frequency that its files' spread shows (their
    // linear frequencies disagree beyond their stated uncertainties: the report's WARNING on the
    // band); None where they agree, or one file or a table gives it.
    const auto sd = spread.find(id);
    d["frequency_spread_std"] =
        sd == spread.end() ? py::object(py::none()) : py::object(py::float_(sd->second));
    modes.append(d);
  }
  return modes;
}

// The MAC at the result, as mac.csv: a row per measured mode ('modes' order), a column per
// model mode from 1 (those up to 1.5 times the highest measured frequency, and past every pair).
py::array_t<double> linear_mac(const correlate::LinearUpdateSummary& s) {
  const Eigen::MatrixXd& mac = s.final.mac;
  const Eigen::Index cols = correlate::mac_columns(s);
  py::array_t<double> mac_array({mac.rows(), cols});
  auto cell = mac_array.mutable_unchecked<2>();
  for (Eigen::Index i = 0; i < mac.rows(); ++i)
    for (Eigen::Index j = 0; j < cols; ++j) cell(i, j) = mac(i, j);
  return mac_array;
}

// update_linear()'s result: the summary as Python values.
py::dict linear_result(const correlate::LinearUpdateSummary& s,
                       const std::map<std::string, double>& spread) {
  py::dict parameters;
  for (const correlate::ParameterReport& p : s.parameters)
    parameters[py::str(p.name)] = linear_parameter(p, s.final.measured_frequency_hz.size());
  const py::list modes = linear_pairs(s.final, spread);
  py::dict result;
  result["parameters"] = parameters;
  result["modes"] = modes;
  result["history"] = linear_history(s);
  result["rule"] = s.rule;
  result["converged"] = s.status == correlate::LinearUpdateStatus::kConverged;
  result["status"] = linear_status_name(s.status);
  // kPairsUnconfirmed: the line naming the pairs, why and what to do ("" otherwise), and the
  // measured modes (as 'modes' numbers them) whose pairs the shapes do not confirm.
  result["unconfirmed"] = s.unconfirmed;
  py::list unconfirmed_modes;
  for (const int i : s.unconfirmed_modes)
    unconfirmed_modes.append(modes[static_cast<size_t>(i)]["measured"]);
  result["unconfirmed_modes"] = unconfirmed_modes;
  result["collinear"] = linear_collinear(s);
  // The standard deviations rest on the residuals' scatter (reduced_chi2 > 1: scaled by its root
  // and widened by Student's t), not on the stated frequency uncertainty.
  result["sigma_from_scatter"] = s.sigma_from_scatter;
  // None where no degree of freedom is left (the summary's 0 there is no chi-square).
  result["degrees_of_freedom"] = s.degrees_of_freedom;
  result["reduced_chi2"] =
      s.degrees_of_freedom > 0 ? py::object(py::float_(s.reduced_chi2)) : py::object(py::none());
  // The fits from different starts behind the result (1, or 1 + the restarts tried where the
  // fit from the start left scatter beyond the noise) and the report's line on them ("": none).
  result["starts"] = s.starts;
  result["restarts"] = s.restarts;
  result["warnings"] = s.warnings;
  result["mac"] = linear_mac(s);
  result["report"] = s.report();
  return result;
}

// update-linear: the same inputs, options and defaults as the command; the result as Python
// values, and the updated model file written when `out` is given.
py::dict update_linear(const PathArg& model_arg, const OneOrMany<std::string>& sets_arg,
                       const PathArg& sensors_arg, const std::optional<PathArg>& measured_arg,
                       const std::optional<PathArg>& modes_table_arg, const std::string& rule,
                       const std::optional<std::string>& minimize, double tolerance,
                       double frequency_window, double mac_threshold, double frequency_std,
                       const OneOrMany<std::string>& hold, const std::optional<PathArg>& out_arg,
                       const py::object& progress, bool trust_signs,
                       const std::map<std::string, std::pair<double, double>>& bounds,
                       const std::optional<std::pair<double, double>>& bound_factors,
                       double alias_mac) {
  check_progress(progress);
  const std::string model_path = text(model_arg), sensors_path = text(sensors_arg);
  const std::optional<std::string> measured = text(measured_arg),
                                   modes_table = text(modes_table_arg), out = text(out_arg);
  const std::vector<std::string>& sets = sets_arg.items;
  if (sets.empty()) throw InputError("update-linear: give at least one set to update (--set)");
  correlate::LinearUpdateOptions o =
      linear_options({rule, minimize, tolerance, frequency_window, mac_threshold, frequency_std,
                      hold.items, trust_signs, bounds, bound_factors, alias_mac});
  if (measured.has_value() == modes_table.has_value())
    throw InputError("update-linear: give either --measured DIR or --modes-table FILE");
  o.progress = [&progress](int iteration, double cost, double largest) {
    report(progress, fmt::format("update-linear: iteration {}, cost {:.4g}, largest frequency "
                                 "error {:.3g} %",
                                 iteration, cost, 100 * largest));
  };
  InterruptCheck interrupted;
  o.interrupt = [&interrupted] { interrupted(); };
  correlate::LinearUpdateSummary s;
  // Per measured mode (by its id), the relative std its files' spread shows (> 0 only).
  std::map<std::string, double> spread;
  {
    py::gil_scoped_release release;
    const model::Model m = model::read_model(model_path);
    const std::vector<correlate::Sensor> sensors = correlate::read_sensors(sensors_path, m);
    const correlate::MeasuredModes meas =
        measured ? correlate::measured_modes(correlate::read_process_run(*measured), sensors,
                                             nullptr, o.frequency_std)
                 : correlate::read_modes_table(*modes_table, sensors, nullptr);
    for (Eigen::Index i = 0; i < meas.frequency_std.size(); ++i)
      if (meas.frequency_std(i) > 0) spread[meas.id(i)] = meas.frequency_std(i);
    const Eigen::VectorXd theta = correlate::update_linear(m, sets, sensors, meas, o, &s);
    if (const std::string why =
            correlate::linear_refusal(s, o, measured ? *measured : *modes_table);
        !why.empty())
      throw InputError("update-linear: " + why);
    const model::Model updated = correlate::StiffnessSets(m, sets).apply(theta);
    if (out) write_model(*out, updated);
  }
  return linear_result(s, spread);
}

// run: a whole campaign into `out`, as `jointlab run`; the summary as a dict. Hits that could
// not be processed and modes without a backbone are listed, not raised (everything else is
// written), as the library reports them.
py::dict run(const PathArg& campaign_arg, const PathArg& out_arg, bool force,
             const Integer& threads_arg, const py::object& progress) {
  check_progress(progress);
  const std::string campaign_file = text(campaign_arg), out = text(out_arg);
  const unsigned threads = threads_option(threads_arg);
  campaign::RunSummary s;
  InterruptCheck interrupted;  // made on the calling thread, the one that checks
  {
    py::gil_scoped_release release;
    const campaign::Campaign c = campaign::read_campaign(campaign_file);
    campaign::RunOptions o;
    o.out = out;
    o.force = force;
    o.threads = threads;
    o.progress = [&progress](const std::string& line) { report(progress, line); };
    o.interrupt = [&interrupted] { interrupted(); };
    s = campaign::run_campaign(c, o);
  }
  py::dict d;
  d["hits"] = s.hits;
  d["hits_processed"] = s.hits_processed;
  d["hits_reused"] = s.hits_reused;
  py::list failed;
  for (const campaign::FailedHit& f : s.failed_hits) failed.append(f.text());
  d["failed_hits"] = failed;
  d["flagged_hits"] = s.flagged_hits;
  // As the report's "model built" / "model up to date": built in this run, or reused.
  d["model_built"] = s.model_built;
  d["model_reused"] = s.model_reused;
  d["notes"] = s.notes;
  d["no_backbone"] = s.no_backbone;
  d["refused"] = s.refused;
  d["stopped"] = s.stopped;
  d["report_html"] = s.report_html.string();
  d["report_markdown"] = s.report_markdown.string();
  d["report"] = s.report();
  return d;
}

// The measured side of update_iwan() and compare() as the command's options name it (absent:
// the option not given).
campaign::IwanInputArgs iwan_input_args(const std::vector<std::string>& modes,
                                        const std::vector<std::string>& backbones,
                                        const std::optional<std::string>& amplitude,
                                        const std::optional<std::string>& dof,
                                        const std::optional<std::string>& measured,
                                        const std::optional<std::string>& sensors,
                                        const std::vector<std::string>& channels) {
  campaign::IwanInputArgs a;
  a.modes = modes;
  a.backbones = backbones;
  a.amplitude = amplitude.value_or("");
  a.dof = dof.value_or("");
  a.measured = measured.value_or("");
  a.sensors = sensors.value_or("");
  a.channels = channels;
  return a;
}

// update-iwan's --stepped-sine, --stepped-sine-channel, --stepped-sine-mode and --pareto (none:
// empty, "", 0: the command's defaults).
struct SteppedSineArgs {
  std::vector<std::string> folders;  // `jointlab stepped-sine` output folders
  std::string channel;               // the sensor channel of their response
  int mode = 0;                      // their elastic model mode (0: the first --mode)
  std::vector<double> pareto;        // gamma values of a Pareto front
};

// update-iwan (contract.md): backbone tables (data/backbone_table.h) or a `process` folder with
// its sensors, read as the command reads them (campaign/iwan_inputs.h); the options and defaults
// of the command; the fit `run` and the command make (campaign::checked_fit_iwan).
py::dict update_iwan(
    const std::string& model_path, const std::string& set, const std::vector<std::string>& modes,
    const std::vector<std::string>& backbones, const std::optional<std::string>& amplitude,
    const std::optional<std::string>& dof, const std::string& linear_damping,
    const std::optional<std::pair<double, double>>& fs_range,
    const std::pair<double, double>& gamma_range, const std::pair<double, double>& chi_range,
    const std::pair<double, double>& beta_range, int evaluations, unsigned seed,
    const std::optional<std::string>& out, const py::object& progress,
    const std::optional<std::string>& measured, const std::optional<std::string>& sensors,
    const std::vector<std::string>& channels, const correlate::IwanUpdateOptions& asked,
    const SteppedSineArgs& sine) {
  if (set.find('.') != std::string::npos && !set.starts_with("iwan."))
    throw InputError(
        fmt::format("--set {}: update-iwan updates an Iwan set (iwan.<name> or "
                    "<name>); springs are updated by update-linear",
                    set));
  if (linear_damping != "hold" && linear_damping != "fit")
    throw InputError(fmt::format("--linear-damping {}: expected hold or fit", linear_damping));
  if (amplitude && *amplitude != "modal" && *amplitude != "displacement" &&
      *amplitude != "velocity" && *amplitude != "acceleration")
    throw InputError(fmt::format(
        "--amplitude {}: expected modal, displacement, velocity or acceleration", *amplitude));
  const campaign::IwanRanges ranges{fs_range, gamma_range, chi_range, beta_range};
  ranges.check();
  correlate::IwanUpdateSummary summary;
  campaign::IwanInputs in;
  std::vector<std::string> shape_warnings;
  std::vector<correlate::ParetoPoint> front;
  std::string text;  // the command's report
  {
    py::gil_scoped_release release;
    const model::Model m = model::read_model(model_path);
    campaign::IwanInputArgs a =
        iwan_input_args(modes, backbones, amplitude, dof, measured, sensors, channels);
    a.model = model_path;
    a.stepped_sine = sine.folders;
    a.stepped_sine_channel = sine.channel;
    a.stepped_sine_mode = sine.mode;
    in = campaign::read_iwan_inputs(m, a, "update-iwan");
    if (!in.slip_screen.empty())
      report(progress,
             "slip screen (points where other modes slip the joints):\n" + in.slip_screen);
    correlate::IwanUpdateOptions o = asked;  // gamma, beta, linear_damping_max, threads
    o.amplitude = in.amplitude;
    o.fit_linear_damping = linear_damping == "fit";
    // As the command: a model whose modes match the measured linear frequencies is said to be
    // linearly updated, not sent to update-linear.
    o.linear_part_updated = campaign::linear_part_matches(m, in.targets);
    o.max_evaluations = evaluations;
    o.seed = seed;
    // Ctrl-C is checked at every evaluation the library reports (a 400-evaluation fit of the
    // example campaign ran its 8 s to the end; the global search reports in batches of 50), and a
    // line goes to `progress` at the first evaluation at or past each multiple of 250: the local
    // solves' count steps over some (a 423-evaluation fit of 400 said nothing). A second fit (beta
    // freed) counts from 0 again.
    InterruptCheck interrupted;
    o.progress = campaign::progress_every(
        250,
        [&progress](int n, double best) {
          report(progress,
                 fmt::format("update-iwan: {} QSMA evaluations, best cost {:.6g}", n, best));
        },
        [&interrupted] { interrupted(); });
    correlate::IwanObjective objective(m, set, in.sensors, in.targets, o);
    if (in.measured) objective.set_linear_modes(*in.measured, 0.6);
    summary =
        campaign::checked_fit_iwan(objective, o, ranges, "update-iwan", in.data_name, nullptr);
    if (!sine.pareto.empty()) {  // as the command: in the search box, after the fit
      o.bounds = ranges.bounds(objective.initial());
      front = correlate::pareto_front(objective, sine.pareto, o);
    }
    const model::Model updated = objective.apply(summary.best, summary.modal_ratio);
    text = campaign::update_iwan_report(summary, m, updated, set, in, front, "--set {}",
                                        &shape_warnings);
    if (out) write_model(*out, updated);
  }
  // One dict per row of parameters.csv (Fs, Kt, chi, beta, gamma = Kt / Ks when known), from
  // the rows the file is written from; modal_ratio always, with its absolute std.
  const std::vector<correlate::IwanParameterRow> rows = correlate::iwan_parameter_rows(summary);
  py::dict parameters;
  bool z_identifiable = false;
  for (const correlate::IwanParameterRow& r : rows) {
    if (r.name == "modal_ratio") {
      z_identifiable = r.identifiable;
      continue;
    }
    // gamma is Kt over the reference stiffness: Kt's hold, sigma, bound and note.
    const int k = r.name == "Fs" ? 0 : r.name == "chi" ? 2 : r.name == "beta" ? 3 : 1;
    py::dict d;
    d["initial"] = r.initial;
    d["final"] = r.final;
    d["relative_std"] = r.relative_std > 0 ? py::object(py::float_(r.relative_std)) : py::none();
    // Held as asked, as parameters.csv's held; beta held by the fit itself is not fitted either.
    d["held"] = r.held;
    d["fitted"] = !summary.held[static_cast<size_t>(k)];
    d["note"] = r.note;
    d["at_bound"] = r.at_bound;
    d["identifiable"] = r.identifiable;
    // The linear part's systematic effect (the report's "linear part:" line): the relative change
    // of the parameter per relative error of mode R's linear frequency from the rest of the
    // model, and the error of that frequency its sigma holds to; None where unknown.
    const double rate = summary.linear_part_sensitivity(k),
                 holds = summary.linear_part_tolerance(k);
    d["linear_part_sensitivity"] = rate != 0 && !r.held ? py::object(py::float_(rate)) : py::none();
    d["linear_part_tolerance"] = holds > 0 ? py::object(py::float_(holds)) : py::none();
    parameters[py::str(r.name)] = d;
  }
  py::dict z;
  z["initial"] = summary.modal_ratio_start;
  z["final"] = summary.modal_ratio;
  z["std"] = summary.modal_ratio_fitted && summary.modal_ratio_std > 0
                 ? py::object(py::float_(summary.modal_ratio_std))
                 : py::object(py::none());
  z["fitted"] = summary.modal_ratio_fitted;
  z["note"] = summary.parameter_note(4);  // as parameters.csv's modal_ratio row
  z["identifiable"] = z_identifiable;
  parameters["modal_ratio"] = z;
  py::dict result;
  result["parameters"] = parameters;
  // A cost the model could not evaluate (+inf) is None, never a number.
  const auto cost = [](double c) -> py::object {
    if (std::isfinite(c)) return py::cast(c);
    return py::none();
  };
  result["cost"] = cost(summary.final_cost);
  result["initial_cost"] = cost(summary.initial_cost);
  result["evaluations"] = summary.evaluations;
  // False: the search stopped before its local solve met its tolerance, and no sigma is stated.
  result["converged"] = summary.status == correlate::IwanUpdateStatus::kConverged;
  // True: Z fitted and the joint no better than a constant backbone (Fs, chi, beta not
  // identified; Kt and modal_ratio are the result).
  result["no_slip"] = summary.no_slip_seen();
  std::vector<std::string> warnings = summary.at_bounds;
  warnings.insert(warnings.end(), shape_warnings.begin(), shape_warnings.end());
  result["warnings"] = warnings;
  result["reduced_chi2"] = summary.reduced_chi2;
  // The residuals' effective number of independent points behind the sigmas (None: unknown).
  result["effective_points"] = summary.effective_points > 0
                                   ? py::object(py::float_(summary.effective_points))
                                   : py::object(py::none());
  result["noise_correlation"] = summary.effective_points > 0
                                    ? py::object(py::float_(summary.noise_correlation))
                                    : py::object(py::none());
  result["sigma_degrees_of_freedom"] =
      summary.effective_points > 0 ? py::object(py::float_(summary.sigma_degrees_of_freedom))
                                   : py::object(py::none());
  // The noise note's other evidence: the largest share of the chi-square one third of the points
  // (by amplitude) holds, about 1/3 for noise (None: unknown); and whether the reduced
  // chi-square lies significantly above 1 (the report's "does not describe the data" WARNING).
  result["amplitude_share"] = summary.amplitude_share > 0
                                  ? py::object(py::float_(summary.amplitude_share))
                                  : py::object(py::none());
  result["misfit"] = summary.misfit();
  // The Pareto front (pareto=): a dict per gamma, and the command's lines in the report.
  py::list pareto;
  for (const correlate::ParetoPoint& p : front) {
    py::dict d;
    d["gamma"] = p.gamma;
    d["Fs"] = p.params.Fs;
    d["Kt"] = p.params.Kt;
    d["chi"] = p.params.chi;
    d["beta"] = p.params.beta;
    d["linear_error"] = p.linear_error;
    d["backbone_cost"] = p.backbone_cost;
    d["dominated"] = p.dominated;
    py::list errors;  // per measured linear mode; None: unpaired
    for (const std::optional<double>& e : p.mode_errors)
      errors.append(e ? py::object(py::float_(*e)) : py::object(py::none()));
    d["mode_errors"] = errors;
    pareto.append(d);
  }
  result["pareto"] = pareto;
  // Every evaluation the model could evaluate, as history.csv: its number, cost and the best so
  // far, and whether beta was held (the file's stage, "beta held" or "beta free").
  {
    std::vector<const correlate::IwanHistoryEntry*> kept;
    for (const correlate::IwanHistoryEntry& h : summary.history)
      if (std::isfinite(h.cost)) kept.push_back(&h);
    const auto n = static_cast<Eigen::Index>(kept.size());
    Eigen::VectorXd evaluation(n), objective(n), best(n);
    py::array_t<bool> beta_held(n);
    auto held = beta_held.mutable_unchecked<1>();
    for (Eigen::Index i = 0; i < n; ++i) {
      const correlate::IwanHistoryEntry& h = *kept[static_cast<size_t>(i)];
      evaluation(i) = h.evaluation;
      objective(i) = h.cost;
      best(i) = h.best;
      held(i) = h.beta_held;
    }
    py::dict history;
    history["evaluation"] = to_numpy(std::move(evaluation));
    history["objective"] = to_numpy(std::move(objective));
    history["best"] = to_numpy(std::move(best));
    history["beta_held"] = beta_held;
    result["history"] = history;
  }
  result["report"] = text;
  return result;
}

// `jointlab compare` without the figure unless `out` names one: the measured curves and each
// model's QSMA backbone over their range (campaign/model_comparison.h).
py::dict compare(const OneOrMany<PathArg>& model_args, const py::object& mode,
                 const OneOrMany<PathArg>& backbone_args,
                 const std::optional<std::string>& amplitude, const std::optional<std::string>& dof,
                 const std::optional<PathArg>& measured_arg,
                 const std::optional<PathArg>& sensors_arg,
                 const OneOrMany<std::string>& channels_arg,
                 const OneOrMany<std::string>& labels_arg, const Integer& points_arg,
                 const std::optional<PathArg>& out_arg) {
  const std::vector<std::string> models = text(model_args.items),
                                 backbones = text(backbone_args.items);
  const std::vector<std::string>&channels = channels_arg.items, &labels = labels_arg.items;
  const std::optional<std::string> measured = text(measured_arg), sensors = text(sensors_arg),
                                   out = text(out_arg);
  const int points = static_cast<int>(in_range(points_arg, "--points", 2, 100000));
  if (out) {
    const std::string ext = std::filesystem::path(*out).extension().string();
    if (ext != ".png" && ext != ".svg" && ext != ".pdf")
      throw InputError(fmt::format("--out {}: the figure must end in .png, .svg or .pdf", *out));
  }
  std::vector<std::string> modes;
  if (py::isinstance<py::str>(mode))
    modes = {mode.cast<std::string>()};
  else if (is_integer(mode))
    modes = {integer_text(mode)};
  else
    throw InputError("mode: expected an int or 'R:BAND'");
  const campaign::IwanInputArgs a =
      iwan_input_args(modes, backbones, amplitude, dof, measured, sensors, channels);
  // The figure's folder, made before the curves are computed: one that cannot be made is the
  // user's mistake, said as such (it was a RuntimeError after the QSMA curves).
  if (out) {
    const std::filesystem::path folder = std::filesystem::path(*out).parent_path();
    std::error_code ec;
    if (!folder.empty()) std::filesystem::create_directories(folder, ec);
    if (ec || !(folder.empty() || std::filesystem::is_directory(folder)))
      throw InputError(fmt::format("{}: cannot create the output directory", folder.string()));
  }
  campaign::ModelComparison c;
  {
    py::gil_scoped_release release;
    c = campaign::compare_models(models, labels, a, points);
    if (out) {
      const std::filesystem::path figure(*out);
      campaign::plot_backbone_comparison(c.figure, figure,
                                         std::filesystem::path(figure).replace_extension(".csv"));
    }
  }
  for (const std::string& note : c.notes)
    if (PyErr_WarnEx(PyExc_UserWarning, note.c_str(), 1) != 0) throw py::error_already_set();
  py::list measured_curves;
  for (correlate::MeasuredBackbone& b : c.figure.measured) {
    py::dict d;
    d["source"] = b.source;
    d["amplitude"] = to_numpy(std::move(b.amplitude));
    d["frequency_hz"] = to_numpy(std::move(b.frequency_hz));
    d["damping_ratio"] = to_numpy(std::move(b.damping_ratio));
    measured_curves.append(d);
  }
  py::list model_curves;
  for (size_t i = 0; i < c.figure.models.size(); ++i) {
    campaign::ModelCurve& m = c.figure.models[i];
    py::dict d;
    d["label"] = m.label;
    d["amplitude"] = to_numpy(std::move(m.amplitude));
    d["frequency_hz"] = to_numpy(std::move(m.frequency_hz));
    d["damping_ratio"] = to_numpy(std::move(m.damping));
    d["clipped"] = static_cast<bool>(c.clipped[i]);
    model_curves.append(d);
  }
  py::dict result;
  result["title"] = c.figure.title;
  result["amplitude_label"] = c.figure.amplitude_label;
  result["measured"] = measured_curves;
  result["models"] = model_curves;
  result["slip_screen"] = c.slip_screen;
  return result;
}

// update_iwan with `mode` as Python gives it: an int, an 'R:BAND' string or a list of either.
py::dict update_iwan_call(
    const PathArg& model, const std::string& set, const py::object& mode,
    const OneOrMany<PathArg>& backbones, const std::optional<std::string>& amplitude,
    const std::optional<std::string>& dof, const std::string& linear_damping,
    const std::optional<std::pair<double, double>>& fs_range,
    const std::pair<double, double>& gamma_range, const std::pair<double, double>& chi_range,
    const std::pair<double, double>& beta_range, const Integer& evaluations_arg,
    const Integer& seed_arg, const std::optional<PathArg>& out, const py::object& progress,
    const std::optional<PathArg>& measured, const std::optional<PathArg>& sensors,
    const OneOrMany<std::string>& channels, std::optional<double> gamma, std::optional<double> beta,
    double linear_damping_max, const Integer& threads, const std::string& optimizer,
    const std::string& compare, const OneOrMany<PathArg>& stepped_sine,
    const std::optional<std::string>& stepped_sine_channel, const Integer& stepped_sine_mode_arg,
    const OneOrMany<double>& pareto_arg) {
  check_progress(progress);
  const std::vector<double>& pareto = pareto_arg.items;
  // --seed, a UINT as the command reads it (-1 was pybind11's "incompatible function arguments").
  const auto seed = static_cast<unsigned>(in_range(seed_arg, "--seed", 0, 4294967295LL));
  const int stepped_sine_mode = as_int(stepped_sine_mode_arg, "--stepped-sine-mode", 0);
  if (stepped_sine_mode < 0)
    throw InputError(
        fmt::format("--stepped-sine-mode {}: elastic modes count from 1 (0: the first mode)",
                    stepped_sine_mode));
  for (const double g : pareto) {
    if (!(std::isfinite(g) && g > 0))
      throw InputError(fmt::format("--pareto {}: gamma values must be finite and > 0", g));
  }
  const SteppedSineArgs sine{text(stepped_sine.items), stepped_sine_channel.value_or(""),
                             stepped_sine_mode, pareto};
  // --gamma, --beta, --linear-damping-max and --threads, checked as the command checks them.
  correlate::IwanUpdateOptions asked;
  if (gamma) {
    if (!(std::isfinite(*gamma) && *gamma > 0))
      throw InputError(fmt::format("--gamma {}: must be a finite number > 0", *gamma));
    asked.fixed_gamma = *gamma;
  }
  if (beta) {
    if (!(std::isfinite(*beta) && *beta >= 0))
      throw InputError(
          fmt::format("--beta {}: must be a finite number >= 0 (0: no macroslip weight)", *beta));
    asked.fixed_beta = *beta;
  }
  if (!(linear_damping_max >= 1e-9 && linear_damping_max <= 0.999))
    throw InputError(
        fmt::format("--linear-damping-max {}: must be in [1e-09, 0.999]", linear_damping_max));
  asked.linear_damping_max = linear_damping_max;
  asked.threads = static_cast<int>(threads_option(threads));
  // --optimizer and --compare.
  if (optimizer != "paper" && optimizer != "paper-log" && optimizer != "global-local")
    throw InputError(
        fmt::format("--optimizer {}: expected paper, paper-log or global-local", optimizer));
  asked.optimizer = optimizer == "paper"       ? correlate::IwanOptimizer::kPaper
                    : optimizer == "paper-log" ? correlate::IwanOptimizer::kPaperLog
                                               : correlate::IwanOptimizer::kGlobalLocal;
  if (compare != "matched" && compare != "secant")
    throw InputError(fmt::format("--compare {}: expected matched or secant", compare));
  asked.comparison = compare == "secant" ? correlate::IwanComparison::kSecant
                                         : correlate::IwanComparison::kMatched;
  std::vector<std::string> modes;
  const auto one = [&](const py::handle& h) {
    if (py::isinstance<py::str>(h))
      modes.push_back(h.cast<std::string>());
    else if (is_integer(h))
      modes.push_back(integer_text(h));
    else
      throw InputError("mode: expected an int, 'R:BAND' or a list of them");
  };
  // A list, a tuple or a numpy array of modes (np.array([1, 2]) was read as one integer).
  if (py::isinstance<py::list>(mode) || py::isinstance<py::tuple>(mode) ||
      (py::isinstance<py::array>(mode) && py::reinterpret_borrow<py::array>(mode).ndim() > 0)) {
    for (const py::handle h : mode) one(h);
  } else {
    one(mode);
  }
  if (modes.empty()) throw InputError("mode: give at least one mode");
  return update_iwan(text(model), set, modes, text(backbones.items), amplitude, dof, linear_damping,
                     fs_range, gamma_range, chi_range, beta_range,
                     as_int(evaluations_arg, "--evaluations", 1), seed, text(out), progress,
                     text(measured), text(sensors), channels.items, asked, sine);
}

// build-model: the description's reduced model written to `out` as the command writes it (M.mtx,
// K.mtx, dofs.csv, model.toml), then read back as a Model.
Model build_model(const PathArg& description_arg, const PathArg& out_arg,
                  const std::optional<Integer>& modes, const py::object& progress) {
  check_progress(progress);
  const std::string description = text(description_arg), out = text(out_arg);
  // --modes, non-negative as the command takes it.
  const std::optional<int> interface_modes =
      modes ? std::optional<int>(
                  static_cast<int>(in_range(*modes, "--modes", 0, std::numeric_limits<int>::max())))
            : std::nullopt;
  InterruptCheck interrupted;
  {
    py::gil_scoped_release release;
    model::fe::RivetedBeamDescription d = model::fe::read_riveted_beam_description(description);
    if (interface_modes) d.fixed_interface_modes = *interface_modes;
    model::fe::BuildOptions options;
    options.progress = [&progress](const std::string& line) { report(progress, line); };
    options.interrupt = [&interrupted] { interrupted(); };
    const model::fe::ReducedModel m = model::fe::build_reduced_model(d, options);
    if (!m.summary.ok)
      throw InputError(fmt::format("{}: the reduction failed: {}", description, m.summary.report));
    model::fe::write_model_directory(out, m);
  }
  return Model(std::filesystem::path(out) / "model.toml");
}

// A model DOF as the command's --impact and --sensors take it: an index (a Python or numpy
// integer) or a "node:component" label.
std::string dof_text(const py::handle& h, const std::string& option) {
  if (py::isinstance<py::str>(h)) return h.cast<std::string>();
  if (is_integer(h)) return integer_text(h);
  throw InputError(fmt::format("{}: expected a DOF index (int) or a 'node:component' label, got {}",
                               option, Py_TYPE(h.ptr())->tp_name));
}

// simulate: a virtual hammer test of the model, the record the command writes (to `out` too,
// when given) as read_record() gives a file, and the energy report the command prints.
py::dict simulate(const py::object& model_arg, const py::object& impact, double force,
                  double duration, double fs, const py::object& sensors_arg, double pulse,
                  double pulse_start, const Integer& substeps, std::optional<double> modal_damping,
                  double rayleigh_mass, double rayleigh_stiffness, double cutoff, double noise,
                  const Integer& seed, bool force_channel, const std::optional<PathArg>& out_arg,
                  const py::object& progress) {
  check_progress(progress);
  const std::optional<std::string> out = text(out_arg);
  // The model: a jointlab.Model (read already) or its file.
  std::optional<model::Model> read;
  const Model* given = py::isinstance<Model>(model_arg) ? &model_arg.cast<const Model&>() : nullptr;
  std::string model_name;
  if (given) {
    model_name = given->path();
  } else {
    try {
      model_name = text(model_arg.cast<PathArg>());
    } catch (const py::cast_error&) {
      throw py::type_error(
          fmt::format("model: expected a model file (str or os.PathLike) or a jointlab.Model; "
                      "got {}",
                      Py_TYPE(model_arg.ptr())->tp_name));
    }
  }
  // --impact and --sensors as text, as the command reads them (one DOF or a list of them).
  const std::string impact_dof = dof_text(impact, "--impact");
  std::vector<std::string> sensors;
  if (py::isinstance<py::str>(sensors_arg) || is_integer(sensors_arg)) {
    sensors.push_back(dof_text(sensors_arg, "--sensors"));
  } else if (py::isinstance<py::iterable>(sensors_arg)) {
    for (const py::handle h : sensors_arg) sensors.push_back(dof_text(h, "--sensors"));
  } else if (!sensors_arg.is_none()) {
    sensors.push_back(dof_text(sensors_arg, "--sensors"));  // says what is expected
  }
  model::SimulationOptions o;
  o.pulse.force = force;
  o.duration = duration;
  o.fs = fs;
  o.pulse.duration = pulse;
  o.pulse.start = pulse_start;
  o.substeps = static_cast<int>(in_range(substeps, "--substeps", 0, 100000));
  o.rayleigh_mass = rayleigh_mass;
  o.rayleigh_stiffness = rayleigh_stiffness;
  o.output_cutoff_hz = cutoff;
  model::RecordOptions record;
  record.noise = noise;
  if (!seed.unsigned_value)
    throw InputError(fmt::format("--seed {}: must be in [0, {}]", seed.text,
                                 std::numeric_limits<std::uint64_t>::max()));
  record.seed = *seed.unsigned_value;
  record.include_force = force_channel;
  record.model_name = model_name;
  if (const std::string e = record.error(); !e.empty()) throw InputError("simulate: --" + e);
  data::Record rec;
  std::string energy;
  {
    py::gil_scoped_release release;
    if (!given) read = model::read_model(model_name);
    const model::Model& m = given ? given->model() : *read;
    // The model's own damping ([damping] modal_ratio) unless modal_damping says otherwise.
    o.modal_damping = modal_damping.value_or(m.modal_ratio);
    o.pulse.dof = model::resolve_dof(m, impact_dof, "--impact");
    if (sensors.empty()) o.sensors.push_back(o.pulse.dof);
    for (const std::string& s : sensors) o.sensors.push_back(model::resolve_dof(m, s, "--sensors"));
    // Everything the record's writing could refuse, refused before the simulation's seconds.
    model::check_sensors(m, o.sensors);
    if (out) data::check_record_destination(*out);
    o.progress = [&progress](const std::string& line) { report(progress, line); };
    model::SimulationSummary summary;
    const model::SimulatedResponse r = model::simulate_ringdown(m, o, &summary);
    if (summary.status != model::SimulationStatus::kOk)
      throw InputError(
          fmt::format("simulate: {}: {}; no record is written (a smaller step, substeps, may help)",
                      model_name, summary.message));
    rec = model::make_simulated_record(m, o, r, summary, record);
    if (out) data::write_record(*out, rec);
    energy = summary.report();
  }
  py::dict d = record_dict(std::move(rec));
  d["report"] = energy;
  return d;
}

/// One backbone of stepped_sine(): a file's points, as its backbone CSV (set as attributes).
struct SineBackbone {
  std::string file;                  // the stepped-sine file
  std::string amplitude_quantity;    // what .amplitude measures ("velocity", ...)
  std::string amplitude_unit;        // its SI unit ("m/s")
  std::vector<std::string> reports;  // one line per level: its point, or why it gave none
};

// stepped-sine: each file's levels fitted as the command fits them, a SineBackbone per file with
// a usable point; the command's folder written to `out` when given (the `stepped_sine` folders
// of update_iwan).
py::list stepped_sine(const OneOrMany<PathArg>& file_args, const std::string& amplitude,
                      const std::optional<std::string>& quantity_arg,
                      const std::string& damping_model, const Integer& residual_terms,
                      double coverage_factor, const std::optional<PathArg>& out_arg,
                      const py::object& progress) {
  check_progress(progress);
  const std::vector<std::string> files = text(file_args.items);
  const std::optional<std::string> out = text(out_arg);
  if (files.empty()) throw InputError("stepped-sine: no file given");
  modal::SteppedSineOptions opt;
  opt.amplitude = motion_quantity("--amplitude", amplitude);
  if (damping_model != "hysteretic" && damping_model != "viscous")
    throw InputError(
        fmt::format("--damping-model {}: expected hysteretic or viscous", damping_model));
  opt.damping =
      damping_model == "viscous" ? modal::SineDamping::kViscous : modal::SineDamping::kHysteretic;
  opt.residual_terms = static_cast<int>(in_range(residual_terms, "--residual-terms", 0, 2));
  if (!(coverage_factor >= 1 && coverage_factor <= 10))
    throw InputError(fmt::format("--coverage-factor {}: must be in [1, 10]", coverage_factor));
  opt.coverage_factor = coverage_factor;
  if (const std::string why = opt.check(); !why.empty()) throw InputError(why);
  std::optional<Quantity> quantity;
  if (quantity_arg) quantity = motion_quantity("--quantity", *quantity_arg);
  data::check_distinct_stems(files);
  std::vector<modal::SteppedSineFileResult> results;
  {
    py::gil_scoped_release release;
    for (const std::string& f : files) {
      modal::SteppedSineFileResult r = modal::extract_stepped_sine_file(f, quantity, opt);
      r.source = f;
      for (size_t i = 0; i < r.tables.size(); ++i)
        report(progress, fmt::format("{} {}: {}", f, r.tables[i].label, r.points[i].report()));
      results.push_back(std::move(r));
    }
    if (out) {
      const std::filesystem::path dir(*out);
      std::error_code ec;
      std::filesystem::create_directories(dir, ec);
      if (!std::filesystem::is_directory(dir))
        throw InputError(where(*out, 0, "cannot create output directory"));
      for (const modal::SteppedSineFileResult& r : results) modal::write_sine_backbone(dir, r);
      modal::write_sine_summary(dir, results, opt);
    }
  }
  py::list backbones;
  for (const modal::SteppedSineFileResult& r : results) {
    // A file no level of which gave a point: the command writes its levels' reasons to
    // summary.json alone; here a warning says so (each level's reason is a progress line).
    if (modal::usable_points(r) == 0) {
      const std::string message = fmt::format(
          "stepped-sine: {}: no level gave a usable point (of {})", r.source, r.tables.size());
      if (PyErr_WarnEx(PyExc_UserWarning, message.c_str(), 1) != 0) throw py::error_already_set();
      continue;
    }
    SineBackbone b;
    b.file = r.source;
    b.amplitude_quantity = quantity_name(opt.amplitude);
    b.amplitude_unit = si_unit(opt.amplitude);
    for (size_t i = 0; i < r.tables.size(); ++i)
      b.reports.push_back(fmt::format("{}: {}", r.tables[i].label, r.points[i].report()));
    py::object o = py::cast(std::move(b));
    for (auto item : to_dict(modal::sine_backbone_table(r))) o.attr(item.first) = item.second;
    backbones.append(o);
  }
  // As the command: no backbone at all is an error (the levels' reasons went to `progress`).
  if (backbones.empty())
    throw InputError(fmt::format(
        "stepped-sine: no backbone from any of the {} file(s): no point is usable (each level's "
        "reason is a progress line{})",
        results.size(), out ? fmt::format(" and in {}/summary.json", *out) : ""));
  return backbones;
}

}  // namespace
}  // namespace jointlab::python

PYBIND11_MODULE(jointlab, m) {
  using namespace jointlab::python;
  // Ceres logs through glog; its lines ("Logging before InitGoogleLogging", a rejected trial
  // point) reach no user of the program (apps/main.cc) and, as the docs promise, none of the
  // module: nothing is printed unless a progress callable is given.
  FLAGS_minloglevel = google::GLOG_FATAL;
  m.doc() = R"(jointlab: amplitude-dependent frequency and damping of jointed structures.

The same library as the `jointlab` program: ring-down and stepped-sine processing, the
riveted beam's reduced model, linear modes, Quasi-Static Modal Analysis and virtual hammer
tests of Iwan-jointed models, and model updating. SI units everywhere; arrays are numpy
arrays named as the program's CSV columns. A user's mistake raises jointlab.InputError (a
ValueError) with the program's one-line message. Nothing is printed unless a progress
callable is given.

    import jointlab
    bb = jointlab.process(["hammer_impact.csv"], bands=[(70, 90)], channels=["acc1"])
    print(bb[0].linear_frequency_hz, bb[0].frequency_hz[:5], bb[0].damping_ratio[:5])
    model = jointlab.Model("model.toml")
    print(model.modes(count=10))              # elastic natural frequencies [Hz]
    curve = model.qsma(mode=1, points=60)     # dict of numpy arrays
)";
  py::register_exception<jointlab::InputError>(m, "InputError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr e) {
    try {
      if (e) std::rethrow_exception(e);
    } catch (const Interrupted&) {
      PyErr_SetNone(PyExc_KeyboardInterrupt);
    }
  });
  // The program's version ("jointlab 0.1.0" from `jointlab --version`), without the name.
  {
    const std::string version = jointlab::campaign::program_version();
    m.attr("__version__") = version.substr(version.find(' ') + 1);
  }

  py::class_<Backbone>(m, "Backbone", py::dynamic_attr(),
                       "One backbone of process(): .file, .channel, .band (1-based), "
                       ".linear_frequency_hz [Hz], .linear_damping_ratio and their expanded "
                       "uncertainties .linear_frequency_std_hz, .linear_damping_std (None where "
                       "the band has no linear values: .linear_reason says why), "
                       ".complex_amplitude [m] "
                       "(operating-shape entry), .report, and numpy arrays named as the backbone "
                       "CSV's columns: .time_s [s], .amplitude [SI of the amplitude quantity], "
                       ".frequency_hz [Hz], .damping_ratio, .frequency_std_hz [Hz], .damping_std "
                       "(expanded, k = .coverage_factor), .damped_frequency_hz, "
                       ".decay_rate_1_per_s, .displacement_m, .snr, .window_s, .harmonic, "
                       ".exchange (1 where the mode exchanges energy with another: damping "
                       "apparent), .reference (True for the band's reference channel in its "
                       "file, summary.json's reference_channel: the curve update_iwan and compare "
                       "read by default), .amplitude_quantity and .amplitude_unit ('velocity', "
                       "'m/s'), .linear_fit_amplitude_min / _max (the amplitudes the linear "
                       "values were read over), .noise_floor_m [m].")
      .def_readonly("file", &Backbone::file)
      .def_readonly("channel", &Backbone::channel)
      .def_readonly("band", &Backbone::band)
      .def_readonly("linear_frequency_hz", &Backbone::linear_frequency_hz)
      .def_readonly("linear_damping_ratio", &Backbone::linear_damping_ratio)
      .def_readonly("linear_frequency_std_hz", &Backbone::linear_frequency_std_hz)
      .def_readonly("linear_damping_std", &Backbone::linear_damping_std)
      .def_readonly("complex_amplitude", &Backbone::complex_amplitude)
      .def_readonly("report", &Backbone::report)
      .def_readonly("reference", &Backbone::reference)
      .def_readonly("amplitude_quantity", &Backbone::amplitude_quantity,
                    "What .amplitude measures: 'velocity', 'displacement' or 'acceleration'.")
      .def_readonly("amplitude_unit", &Backbone::amplitude_unit,
                    "The SI unit of .amplitude: 'm/s', 'm' or 'm/s^2'.")
      .def_readonly("linear_fit_amplitude_min", &Backbone::linear_fit_amplitude_min,
                    "Lowest amplitude of the straight-line fit behind the linear values [SI of "
                    ".amplitude]: the level the linear frequency was read at, not zero.")
      .def_readonly("linear_fit_amplitude_max", &Backbone::linear_fit_amplitude_max,
                    "Highest amplitude of that fit [SI of .amplitude].")
      .def_readonly("noise_floor_m", &Backbone::noise_floor_m,
                    "Noise floor of the displacement envelope [m].")
      .def_readonly("linear_reason", &Backbone::linear_reason,
                    "Why the linear values are None (every point superharmonic, say), or ''.")
      // Pickled (and so deep-copied, cached, sent to another process) with its arrays: it was
      // "cannot pickle 'jointlab.Backbone' object".
      .def(py::pickle(
          [](const py::object& self) {
            const Backbone& b = self.cast<const Backbone&>();
            return py::make_tuple(b.file, b.channel, b.band, b.linear_frequency_hz,
                                  b.linear_damping_ratio, b.linear_frequency_std_hz,
                                  b.linear_damping_std, b.complex_amplitude, b.report, b.reference,
                                  b.amplitude_quantity, b.amplitude_unit,
                                  b.linear_fit_amplitude_min, b.linear_fit_amplitude_max,
                                  b.linear_reason, b.noise_floor_m, self.attr("__dict__"));
          },
          [](const py::tuple& t) {
            if (t.size() != 17)
              throw jointlab::InputError("Backbone: not a pickled jointlab.Backbone");
            Backbone b;
            b.file = t[0].cast<std::string>();
            b.channel = t[1].cast<std::string>();
            b.band = t[2].cast<int>();
            b.linear_frequency_hz = t[3].cast<std::optional<double>>();
            b.linear_damping_ratio = t[4].cast<std::optional<double>>();
            b.linear_frequency_std_hz = t[5].cast<std::optional<double>>();
            b.linear_damping_std = t[6].cast<std::optional<double>>();
            b.complex_amplitude = t[7].cast<std::complex<double>>();
            b.report = t[8].cast<std::string>();
            b.reference = t[9].cast<bool>();
            b.amplitude_quantity = t[10].cast<std::string>();
            b.amplitude_unit = t[11].cast<std::string>();
            b.linear_fit_amplitude_min = t[12].cast<std::optional<double>>();
            b.linear_fit_amplitude_max = t[13].cast<std::optional<double>>();
            b.linear_reason = t[14].cast<std::string>();
            b.noise_floor_m = t[15].cast<double>();
            return std::make_pair(std::move(b), t[16].cast<py::dict>());
          }))
      .def("__repr__", [](const Backbone& b) {
        if (!b.linear_frequency_hz || !b.linear_damping_ratio)
          return fmt::format("<jointlab.Backbone {} {} band {}: no linear values>", b.file,
                             b.channel, b.band);
        return fmt::format("<jointlab.Backbone {} {} band {}: {:.6g} Hz, zeta {:.4g}>", b.file,
                           b.channel, b.band, *b.linear_frequency_hz, *b.linear_damping_ratio);
      });

  m.def("process", &process, py::arg("files"), py::arg("bands") = py::none(), py::arg("modes") = 0,
        py::arg("channels") = py::none(), py::arg("quantity") = py::none(),
        py::arg("amplitude") = "velocity", py::arg("progress") = py::none(), py::arg("threads") = 0,
        py::arg("method") = "hilbert",
        py::arg("snr_min") = jointlab::modal::RingdownOptions{}.snr_min,
        py::arg("max_damping_std") = jointlab::modal::RingdownOptions{}.max_damping_rel_std,
        py::arg("coverage_factor") = jointlab::modal::RingdownOptions{}.coverage_factor,
        py::arg("min_share") = jointlab::modal::ProcessOptions{}.min_share,
        py::arg("out") = py::none(),
        R"(Impact ring-downs -> natural frequency and damping versus amplitude (`jointlab process`).

files      test files (CSV, UFF 58, MATLAB .mat), one hit each: a list, or one path
bands      (lo, hi) in Hz, one per mode: a list, or one pair; or modes=N for the N strongest
           peaks
channels   channel names to process, a list or one name (default: every non-force channel)
quantity   'acceleration', 'velocity' or 'displacement' for channels without a unit
amplitude  quantity of the amplitude column: 'velocity' (default), 'displacement' [m],
           'acceleration' [m/s^2]
progress   callable taking one line of text, or None (silent): each file, then the command's
           line for each channel and band (the span kept, or why no backbone was given)
threads    workers for each file's bands and channels (0: every core); the results do not depend on it
method, snr_min, max_damping_std, coverage_factor, min_share
           as the command's --method ('hilbert' or 'pff'), --snr-min, --max-damping-std,
           --coverage-factor (k of the stated uncertainties) and --min-share
out        also write the command's output folder here (the backbone CSVs and summary.json that
           update_linear's and update_iwan's `measured` read), or None

Returns a list of jointlab.Backbone, one per file x channel x band with a kept span, in the
order of the files, then bands, then channels. Where the command would fail after writing what
it found (modes=N finding fewer than N modes, or a band with a backbone at no channel of a file),
the list is returned with a UserWarning saying why; each peak modes=N left out is a progress
line. Each carries numpy arrays named as the CSV's columns (time_s, amplitude, frequency_hz,
damping_ratio, frequency_std_hz, damping_std, ...) and its linear values (linear_frequency_hz,
linear_damping_ratio).

    bb = jointlab.process(["hit1.csv"], bands=[(70, 90)], quantity="acceleration")
    import matplotlib.pyplot as plt
    plt.semilogx(bb[0].amplitude, bb[0].frequency_hz)
)");

  m.def("read_record", &read_record, py::arg("path"),
        R"(Reads a test file (CSV, UFF 58 ASCII or binary, MATLAB .mat) as the program does.

Returns a dict: 'source', 'sample_rate_hz' [Hz], 't0_s' [s], 'time_s' (the samples' times
t0_s + i / sample_rate_hz [s], a numpy array), 'channels' (names), 'units' (as written), 'quantities' ('acceleration', ... or None), 'data' (name -> numpy array, SI units),
'metadata' (the file's '# key: value' lines).

    rec = jointlab.read_record("hammer_impact.csv")
    acc1 = rec["data"]["acc1"]          # m/s^2
    plt.plot(rec["time_s"], acc1)
)");

  m.def(
      "update_linear", &update_linear, py::arg("model"), py::arg("sets"), py::arg("sensors"),
      py::arg("measured") = py::none(), py::arg("modes_table") = py::none(),
      py::arg("rule") = "least-squares", py::arg("minimize") = py::none(),
      py::arg("tolerance") = 0.0, py::arg("frequency_window") = 0.5, py::arg("mac_threshold") = 0.6,
      py::arg("frequency_std") = 1e-3, py::arg("hold") = std::vector<std::string>{},
      py::arg("out") = py::none(), py::arg("progress") = py::none(), py::arg("trust_signs") = false,
      py::arg("bounds") = std::map<std::string, std::pair<double, double>>{},
      py::arg("bound_factors") = py::none(), py::arg("alias_mac") = 0.9,
      R"(Updates named joint stiffness sets to measured linear frequencies (`jointlab update-linear`).

model          model file (TOML)
sets           element names to update, e.g. ["iwan.rivet", "spring.rz"], or one name
sensors        sensors file (channel,dof[,sign])
measured       a `jointlab process` output folder, or modes_table: mode,frequency_hz[,<channel>...]
rule           'least-squares' (default) or 'smallest' (with minimize=NAME, tolerance default 0.01)
frequency_window, mac_threshold, frequency_std, hold=["NAME[=VALUE]"], alias_mac: as the
               command's options
bounds         {"NAME": (lo, hi)}: absolute stiffness bounds of sets (--bound NAME=LO:HI)
bound_factors  (lo, hi): bounds of every other set as factors of its start (default 1e-3, 1e3)
trust_signs    fit with the sensors file's signs even when one channel reads the model reversed
out            write the updated model file here (its matrices beside it), or None
progress       callable taking one line per optimiser iteration, or None. Ctrl-C ends the
               call with KeyboardInterrupt at the next model solve (0.1 s of checking), in the
               fit, its refits, sweeps and chi-square profile alike

Pairs are made by sensor MAC within the frequency window and followed by full shape (see
docs/update-linear.md). Returns a dict: 'parameters' (name -> initial, final [N/m or N*m/rad],
relative_std (one sigma, relative) or None, slope_std (where relative_std is the chi-square
profile's, wider: the local slope's, which the report says understates it; else None),
sensitivity, flat, held, held_by_user (held by `hold`), at_bound, identifiable, acts_with,
one_sided (+1 / -1: bound by the frequencies from below / above only), smallest_within_tolerance
(None: not lowered), lower, upper (its bounds), sweep (the one-at-a-time sweep, as sweeps.csv:
arrays factor, stiffness, rms_error, errors [point, measured mode]; NaN where no pair was
followed)), 'history' (as history.csv: arrays iteration, objective and each set's stiffness),
'modes' (measured, frequency_hz, model_mode, model_frequency_hz, error
(relative), mac; None where unpaired; frequency_spread_std: the relative one-sigma spread of the
files' linear frequencies where they disagree, the report's WARNING on the band, else None), 'rule',
'converged' (False also where the shapes do not confirm the pairs at the result), 'status'
('converged', 'iteration_limit', 'failed' or 'pairs_unconfirmed'), 'unconfirmed' (the report's
line on pairs the shapes do not confirm, or ''), 'unconfirmed_modes' (their measured modes),
'collinear' (sets acting together: sets, determined, correlation and, for two sets a and b, the
combination theta_a + weight theta_b determined: weight, value, relative_std),
'mac' (the MAC matrix at the result, as mac.csv: a row per measured mode, a column per
model mode from 1), 'degrees_of_freedom' (pairs less fitted sets), 'reduced_chi2' (None where none is left),
'sigma_from_scatter' (True: the sigmas rest on the residuals' scatter, not the stated noise),
'starts' (fits from different starts behind the result), 'restarts' (the report's line on them,
or ''), 'warnings', 'report'. Undecidable pairs, a channel reading the model reversed and shapes without
phase raise InputError saying which.

    r = jointlab.update_linear("model.toml", ["iwan.rivet"], "sensors.csv", measured="processed")
    r["parameters"]["iwan.rivet"]["final"]
)");

  m.def("update_iwan", &update_iwan_call, py::arg("model"), py::arg("set"), py::arg("mode"),
        py::arg("backbones") = std::vector<std::string>{}, py::arg("amplitude") = py::none(),
        py::arg("dof") = py::none(), py::arg("linear_damping") = "hold",
        py::arg("fs_range") = py::none(),
        py::arg("gamma_range") = std::pair<double, double>{0.05, 2.0},
        py::arg("chi_range") = std::pair<double, double>{-0.95, 0.0},
        py::arg("beta_range") = std::pair<double, double>{0.01, 100.0},
        py::arg("evaluations") = 1500, py::arg("seed") = 1u, py::arg("out") = py::none(),
        py::arg("progress") = py::none(), py::arg("measured") = py::none(),
        py::arg("sensors") = py::none(), py::arg("channels") = std::vector<std::string>{},
        py::arg("gamma") = py::none(), py::arg("beta") = py::none(),
        py::arg("linear_damping_max") = 0.05, py::arg("threads") = 0,
        py::arg("optimizer") = "global-local", py::arg("compare") = "matched",
        py::arg("stepped_sine") = std::vector<std::string>{},
        py::arg("stepped_sine_channel") = py::none(), py::arg("stepped_sine_mode") = 0,
        py::arg("pareto") = std::vector<double>{},
        R"(Updates one Iwan set to measured backbones (`jointlab update-iwan`): backbone tables, or
a `process` output folder with its sensors file.

model           model file (TOML), linear stiffness already updated
set             the Iwan set ('iwan.rivet' or 'rivet')
mode            the elastic model mode: with tables, the one every table belongs to (from 1);
                with `measured`, one or a list of R or 'R:BAND' (--mode, repeatable)
backbones       CSV tables amplitude,frequency_hz,damping_ratio[,frequency_std_hz,damping_std]
amplitude       tables: 'modal' (QSMA modal amplitude q, the default) or 'displacement' [m],
                'velocity' [m/s], 'acceleration' [m/s^2] at model DOF `dof` ('NODE:COMP' or an
                index)
measured, sensors, channels
                instead of tables: a `jointlab process` output folder, its sensors file
                (channel,dof) and, optionally, the channels to use (--measured, --sensors,
                --channel); the folder records its own amplitude quantity
linear_damping  'hold' (the model's [damping] modal_ratio) or 'fit' (identified with the joint)
linear_damping_max
                upper bound of a fitted modal_ratio (default 0.05, --linear-damping-max)
gamma, beta     hold Kt / Ks, or beta (0: no macroslip weight), at this value (--gamma, --beta)
fs_range, gamma_range, chi_range, beta_range, evaluations, seed, threads: as the command's
                options (threads: 0 every core; the result does not depend on it)
optimizer       'global-local' (default), 'paper' or 'paper-log' (--optimizer)
compare         'matched' (default: each backbone against the model pair its test shows) or
                'secant' (QSMA's secant pair, as the paper) (--compare)
stepped_sine, stepped_sine_channel, stepped_sine_mode
                `jointlab stepped-sine` output folders fitted with the hammer data, each
                against the steady-state pair; the sensor channel of their response (default:
                the only sensor) and their model mode (0: the first mode) (--stepped-sine,
                --stepped-sine-channel, --stepped-sine-mode)
pareto          gamma values of a Pareto front (--pareto): 'pareto' in the result, one dict per
                gamma (gamma, Fs, Kt, chi, beta, linear_error, backbone_cost, dominated,
                mode_errors: per measured linear mode, None where unpaired), and the
                command's lines in the report
out             write the updated model file here (its folder created), or None

Returns a dict: 'parameters' (Fs [N], Kt [N/m], chi, beta, and gamma = Kt / Ks as
parameters.csv's row -> initial, final, relative_std or None, held (as asked), fitted (False
where held, as asked or by the fit), at_bound, note and identifiable (as parameters.csv's),
linear_part_sensitivity (the relative change per relative error of mode R's linear frequency
from the rest of the model: the report's 'linear part:' line; -16 moves Kt by -1.6 % per 0.1 %)
and linear_part_tolerance (the relative error of that frequency its sigma holds to), None where
unknown; modal_ratio -> initial, final, std (absolute), fitted, note, identifiable), 'cost', 'initial_cost'
(None where the model cannot be evaluated), 'evaluations', 'converged' (False: the search
stopped short of a minimum and no sigma is stated), 'no_slip' (True where, the structure's own
damping fitted, a constant backbone fits as well: Fs, chi and beta are not identified),
'warnings' (parameters at a bound; a band whose shape does not look like its mode),
'reduced_chi2', 'misfit' (True: the reduced chi-square lies significantly above 1, the report's
WARNING that the model does not describe the data within their stated noise),
'effective_points' (the residuals' effective number of independent points; None where unknown),
'noise_correlation' (their AR(1) coefficient, corrected for what the fit absorbs),
'amplitude_share' (the largest share of the chi-square one third of the points, by amplitude,
holds: about 1/3 for noise; None where unknown), 'sigma_degrees_of_freedom' (the sigmas'
Student's t: effective points less the parameters fitted; 2 or fewer state no sigma),
'pareto' (with `pareto`: one dict per gamma, else []), 'history' (as history.csv: arrays
evaluation, objective, best so far, and beta_held for its stage; evaluations the model could
not evaluate left out), 'report'.

progress        callable taking one line, or None: the slip screen with several modes, and a
                line at the first evaluation at or past each multiple of 250. Ctrl-C ends the
                call with KeyboardInterrupt within an evaluation of the local solves, and
                after the batch of 50 samples of the global search (up to 0.4 s on the
                example campaign on two idle cores, 1.7 s on busy ones).

    r = jointlab.update_iwan("model.toml", "iwan.j", 1, ["bb.csv"], linear_damping="fit")
    r["parameters"]["chi"]["final"], r["parameters"]["modal_ratio"]["final"]
    r = jointlab.update_iwan("model.toml", "rivet", 1, measured="processed",
                             sensors="sensors.csv")
)");

  m.def("compare", &compare, py::arg("models"), py::arg("mode"),
        py::arg("backbones") = std::vector<std::string>{}, py::arg("amplitude") = py::none(),
        py::arg("dof") = py::none(), py::arg("measured") = py::none(),
        py::arg("sensors") = py::none(), py::arg("channels") = std::vector<std::string>{},
        py::arg("labels") = std::vector<std::string>{}, py::arg("points") = 100,
        py::arg("out") = py::none(),
        R"(The QSMA backbones of one or more models over measured ones (`jointlab compare`): the
data of the paper's Figures 5-7, and the figure itself where `out` names one.

models          model files (TOML) sharing their DOFs
mode            the elastic model mode (from 1); with `measured` also 'R:BAND'
backbones, amplitude, dof, measured, sensors, channels
                the measured side, as update_iwan() reads it
labels          a legend name per model (default: the file names)
points          points per model curve (default 100)
out             draw the figure here (.png, .svg, .pdf) with the model curves' CSV beside it

Returns a dict: 'title', 'amplitude_label', 'measured' (one dict per curve: source, amplitude,
frequency_hz, damping_ratio), 'models' (one dict per model: label, amplitude, frequency_hz,
damping_ratio, clipped: the curve stops short of the measured range, also a UserWarning saying
where), 'slip_screen'.

    c = jointlab.compare(["start.toml", "updated.toml"], 1, ["bb.csv"], labels=["start", "fit"])
    c["models"][1]["damping_ratio"]
)");

  m.def("run", &run, py::arg("campaign"), py::arg("out"), py::arg("force") = false,
        py::arg("threads") = 0, py::arg("progress") = py::none(),
        R"(Runs a test campaign (TOML, docs/campaign-file.md) into `out`, as `jointlab run`.

force     recompute even outputs that are up to date
threads   workers for the hits (0: every core)
progress  callable taking one line per step, or None (Ctrl-C: at the next step; building the
          model, at the next step of its eigen-solve)

Returns a dict: 'hits', 'hits_processed', 'hits_reused', 'failed_hits' (one line each),
'flagged_hits', 'model_built' (built in this run), 'model_reused' (the built
model up to date), 'notes', 'no_backbone' (modes no hit gave a backbone for), 'refused' (updates
that refused their data), 'stopped' (why a step was not run: the Iwan update after a linear
update whose pairs the shapes do not confirm), 'report_html', 'report_markdown', 'report'. Bad input (the campaign, its model, DOFs, bands) raises InputError.

    s = jointlab.run("campaign.toml", "out")
    print(s["report_html"])
)");

  py::class_<Model>(m, "Model", R"(A model file (TOML with Matrix Market matrices), read once.

    model = jointlab.Model("model.toml")
    model.modes(count=10)               # elastic natural frequencies [Hz]
    model.shapes(count=10)              # their shapes: a row per DOF (model.dof_labels)
    curve = model.qsma(mode=1, points=60)
    curve["frequency_hz"], curve["damping_ratio"]
)")
      .def(py::init<const PathArg&>(), py::arg("path"), py::call_guard<py::gil_scoped_release>())
      .def_property_readonly("path", &Model::path, "The model file, as given.")
      .def_property_readonly("dofs", &Model::dofs, "The number of matrix DOFs.")
      .def("__repr__", &Model::repr)
      .def_property_readonly("dof_labels", &Model::dof_labels,
                             "'node:component' per matrix index (the file's "
                             "[matrices] dof_labels), or [] where it names none: the rows of "
                             "shapes().")
      .def_property_readonly("modal_ratio", &Model::modal_ratio,
                             "The damping ratio of every elastic mode: the model's [damping] "
                             "modal_ratio, 0 without one (as `jointlab modes` prints it).")
      .def(
          "modes", &Model::modes, py::arg("count") = 20,
          R"(The elastic natural frequencies [Hz] among the lowest `count` modes (as `jointlab modes
--count`, rigid-body modes left out: a free-free model's six count, so count=5 gives none),
every joint at its linear stiffness, ascending.)")
      .def("shapes", &Model::shapes, py::arg("count") = 20,
           R"(The elastic mode shapes of modes(count): a 2-D array, a row per matrix DOF (named
by dof_labels), a column per elastic mode in the order of modes(count), mass-normalised
(phi^T M phi = I, phi in m/sqrt(kg) for translations); each column's sign is the solver's.

    f, phi = model.modes(10), model.shapes(10)
    phi[model.dof_labels.index("9003:3"), 0]   # mode 1 at node 9003, z)")
      .def("qsma", &Model::qsma, py::arg("mode"), py::arg("points") = 50,
           py::arg("qmin") = py::none(), py::arg("qmax") = py::none(),
           R"(Quasi-Static Modal Analysis of elastic mode `mode` (from 1), as `jointlab qsma`.

points      number of points (default 50)
qmin, qmax  modal amplitude range (default: microslip to macroslip or the limit load)

Returns a dict of numpy arrays named as the qsma CSV's columns: force_amplitude,
modal_amplitude, frequency_hz [Hz], damping_ratio, max_slip [m], ringdown_frequency_hz,
ringdown_damping_ratio, harmonic_damping_ratio; and 'message' (why the curve ends).)");

  m.def("build_model", &build_model, py::arg("description"), py::arg("out"),
        py::arg("modes") = py::none(), py::arg("progress") = py::none(),
        R"(Builds the riveted beam's reduced model from a description (`jointlab build-model`).

description  riveted beam description (TOML, SI units: docs/model-description.md)
out          the model folder to write (created if missing): M.mtx, K.mtx, dofs.csv and
             model.toml, as the command writes them
modes        fixed-interface modes kept (--modes; default: the description's
             reduction.fixed_interface_modes)
progress     callable taking one line per step (generating, assembling, factorising, the
             fixed-interface eigen-solve, ...), or None. Ctrl-C ends the call with
             KeyboardInterrupt at the next step, within the eigen-solve at its next Lanczos
             step (0.01 to 0.1 s on the example beam); `out` is then not written

Returns the jointlab.Model of out/model.toml: K [N/m, N, N*m] and M [kg, kg*m, kg*m^2] of the
structure on its boundary DOFs and fixed-interface modes, the rivets' joints at their starting
values. The command's check of the reduced against the full model's frequencies (without
--skip-check) is not made here: the program makes it.

    model = jointlab.build_model("examples/riveted_beam/description.toml", "model")
    model.modes(count=16)       # elastic frequencies [Hz], joints at their linear stiffness
)");

  m.def("simulate", &simulate, py::arg("model"), py::arg("impact"), py::arg("force"),
        py::arg("duration"), py::arg("fs"), py::arg("sensors") = py::none(),
        py::arg("pulse") = jointlab::model::HalfSinePulse{}.duration,
        py::arg("pulse_start") = jointlab::model::HalfSinePulse{}.start, py::arg("substeps") = 0,
        py::arg("modal_damping") = py::none(), py::arg("rayleigh_mass") = 0.0,
        py::arg("rayleigh_stiffness") = 0.0, py::arg("cutoff") = 0.0, py::arg("noise") = 0.0,
        py::arg("seed") = 1, py::arg("force_channel") = false, py::arg("out") = py::none(),
        py::arg("progress") = py::none(),
        R"(A virtual hammer test (`jointlab simulate`): the model struck at one DOF by a half-sine
force pulse, its ring-down integrated (Newmark average acceleration, exact Iwan hysteresis) and
the sensors' accelerations recorded.

model          a model file (TOML) or a jointlab.Model
impact         the struck DOF: a 0-based index or a 'node:component' label ('9001:3')
force          peak force of the pulse [N]
duration       record length [s]
fs             sample rate of the record [Hz]
sensors        recorded DOFs, one or a list (default: the impact DOF)
pulse          pulse length [s] (default 0.0005)
pulse_start    time the pulse starts (pre-trigger) [s] (default 0.01)
substeps       integration steps per sample (0: automatic, the Newmark period error of the
               first elastic mode below 1e-5, at least 4)
modal_damping  damping ratio of every elastic mode (default: the model's [damping]
               modal_ratio, 0 without one)
rayleigh_mass, rayleigh_stiffness
               alpha [1/s] and beta [s] of C = alpha M + beta K (default 0)
cutoff         modes above this frequency are left out of the recorded signals [Hz]
               (0: 0.45 fs)
noise          white noise standard deviation as a fraction of each channel's peak (default 0)
seed           noise seed (default 1)
force_channel  also record the hammer force, channel 'hammer' [N]
out            also write the record here (.csv, .uff, .mat) as the command writes it, or None
progress       callable taking a line per 10 % of the run, or None (Ctrl-C: at the next line)

Returns the record as read_record() returns a file: 'source', 'sample_rate_hz' [Hz], 't0_s' [s],
'time_s' [s], 'channels' (acc_<node>_<component> or acc_<index>), 'units', 'quantities',
'data' (name -> numpy array: m/s^2, and N for the hammer), 'metadata' (the file's '# key:
value' lines but fs and t0: model, impact_dof, force_N, pulse_s, ..., energy_closure), and
'report' (the
run's termination, step and energy balance, as the command prints it). The same numbers as
the command's file, bit for bit.

    rec = jointlab.simulate("model.toml", "9001:3", force=200, duration=2, fs=4096,
                            sensors=["9001:3", "9003:3"], out="hit.csv")
    bb = jointlab.process("hit.csv", bands=(100, 145))
)");

  py::class_<SineBackbone>(
      m, "SineBackbone", py::dynamic_attr(),
      "One file's backbone of stepped_sine(): .file, .amplitude_quantity and .amplitude_unit "
      "('velocity', 'm/s'), .reports (a line per level: its point, or why it gave none) and numpy "
      "arrays named as the backbone CSV's columns, a row per level with a point, amplitude "
      "increasing: .amplitude [SI of the amplitude quantity], .frequency_hz [Hz], "
      ".damping_ratio, .frequency_std_hz [Hz], .damping_std (k sigma), .level, "
      ".response_controlled (1: the sweep held the response; 0: the force, its damping from the "
      "energy balance), .points (steps), .fit_rms, .displacement_m [m], .force_n [N], "
      ".damping_direct (0: from the energy balance, less direct). vars(b) is the CSV's table.")
      .def_readonly("file", &SineBackbone::file)
      .def_readonly("amplitude_quantity", &SineBackbone::amplitude_quantity,
                    "What .amplitude measures: 'velocity', 'displacement' or 'acceleration'.")
      .def_readonly("amplitude_unit", &SineBackbone::amplitude_unit,
                    "The SI unit of .amplitude: 'm/s', 'm' or 'm/s^2'.")
      .def_readonly("reports", &SineBackbone::reports,
                    "One line per level of the file: its point, or why it gave none.")
      .def(py::pickle(
          [](const py::object& self) {
            const SineBackbone& b = self.cast<const SineBackbone&>();
            return py::make_tuple(b.file, b.amplitude_quantity, b.amplitude_unit, b.reports,
                                  self.attr("__dict__"));
          },
          [](const py::tuple& t) {
            if (t.size() != 5)
              throw jointlab::InputError("SineBackbone: not a pickled jointlab.SineBackbone");
            SineBackbone b;
            b.file = t[0].cast<std::string>();
            b.amplitude_quantity = t[1].cast<std::string>();
            b.amplitude_unit = t[2].cast<std::string>();
            b.reports = t[3].cast<std::vector<std::string>>();
            return std::make_pair(std::move(b), t[4].cast<py::dict>());
          }))
      .def("__repr__", [](const py::object& self) {
        const SineBackbone& b = self.cast<const SineBackbone&>();
        return fmt::format("<jointlab.SineBackbone {}: {} points>", b.file,
                           py::len(self.attr("amplitude")));
      });

  m.def("stepped_sine", &stepped_sine, py::arg("files"), py::arg("amplitude") = "velocity",
        py::arg("quantity") = py::none(), py::arg("damping_model") = "hysteretic",
        py::arg("residual_terms") = jointlab::modal::SteppedSineOptions{}.residual_terms,
        py::arg("coverage_factor") = jointlab::modal::SteppedSineOptions{}.coverage_factor,
        py::arg("out") = py::none(), py::arg("progress") = py::none(),
        R"(Stepped-sine sweeps -> one backbone point per level (`jointlab stepped-sine`).

files            stepped-sine files, a list or one path: CSV (docs/stepped-sine-table.md) or
                 the .mat struct layout of the Brake-Reuss data
amplitude        the amplitude column: 'velocity' (default) [m/s], 'displacement' [m] or
                 'acceleration' [m/s^2], each at the natural frequency
quantity         what a response column without a [unit] measures (SI assumed):
                 'acceleration', 'velocity' or 'displacement'; None: such a column is an error
damping_model    'hysteretic' (default) or 'viscous' (--damping-model)
residual_terms   other modes' share in the band: 0 none, 1 a complex constant, 2 constant and
                 slope (default)
coverage_factor  k of the stated uncertainties k*sigma (default 3, as process; 1: one sigma)
out              also write the command's folder here (<stem>.backbone.csv, summary.json):
                 what update_iwan's stepped_sine= reads; or None
progress         callable taking one line per level (its point, or why none), or None

Response-controlled sweeps are fitted with a single-mode FRF (f_n, zeta and their
uncertainties from the fit, at the response amplitude at f_n); force-controlled ones give their
phase resonance and the energy balance's damping (docs/stepped-sine.md). Returns a list of
jointlab.SineBackbone, one per file with a usable point, in the order of the files, each with
numpy arrays named as its backbone CSV's columns (amplitude, frequency_hz, damping_ratio,
frequency_std_hz, damping_std, level, response_controlled, ...). A file without a usable point
gives a UserWarning; no point in any file, InputError. The figure (--figure, --ringdown) is the
program's.

    sine = jointlab.stepped_sine("forced_frequency_responses.mat", out="sine")
    sine[0].amplitude, sine[0].frequency_hz, sine[0].damping_ratio
)");
}
