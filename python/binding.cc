// The Python module's shared conversions (binding.h).
#include "binding.h"

#include <limits>

#include <fmt/format.h>

#include "jointlab/model/model_file_writer.h"

namespace jointlab::python {

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
                   std::string_view note) {
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

}  // namespace jointlab::python
