// The Python module's shared pieces (python/*_binding.cc): the argument types every binding
// takes (one value or a list, integers of any size, paths), numpy arrays over the library's
// vectors, progress lines and Ctrl-C, and the functions that add each group of commands to the
// module, one file per group as the command line has one per command (style.md 13). Argument
// conversion only: every number comes from the library the program uses.
#pragma once

#include <atomic>
#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>
#include <Eigen/Core>

#include "jointlab/core/error.h"
#include "jointlab/data/record.h"
#include "jointlab/data/table_writer.h"
#include "jointlab/model/model_file.h"

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

/// A numpy array over the vector's own storage (moved into a capsule numpy frees), no copy.
py::array_t<double> to_numpy(Eigen::VectorXd v);
/// A matrix as a 2-D numpy array over its own storage (column-major), no copy.
py::array_t<double> to_numpy(Eigen::MatrixXd m);
/// A table's columns as a dict of numpy arrays, named as the CSV's header.
py::dict to_dict(data::Table table);
/// A record as read_record() and simulate() return it: its channels as numpy arrays (SI).
py::dict record_dict(data::Record rec);

/// A file or folder argument: a str or any os.PathLike (pathlib.Path), as open() takes them.
using PathArg = std::filesystem::path;
/// The path as the library takes it.
std::string text(const PathArg& p);
/// The path as the library takes it, or none.
std::optional<std::string> text(const std::optional<PathArg>& p);
/// The paths as the library takes them.
std::vector<std::string> text(const std::vector<PathArg>& v);

/// An integer as a mode number: a Python int or a numpy integer (np.arange's, say), not a bool.
bool is_integer(const py::handle& h);
/// An integer's decimal text, however large, for the command's reader to judge.
std::string integer_text(const py::handle& h);
/// An integer option in [lo, hi]; InputError "OPTION V: must be in [LO, HI]NOTE" otherwise.
long long in_range(const Integer& v, std::string_view option, long long lo, long long hi,
                   std::string_view note = "");
/// An integer option as an int; beyond C's range, InputError with the range [lo, INT_MAX].
int as_int(const Integer& v, std::string_view option, int lo);
/// --threads, as the commands take it (0: every core).
unsigned threads_option(const Integer& v);

/// The model file `path` (its matrices beside it), its folder created if missing.
void write_model(const std::string& path, const model::Model& m);
/// One progress line to a Python callable (or nowhere); a pending Ctrl-C raises.
void report(const py::object& progress, const std::string& line);
/// Refuses a `progress` that is neither None nor callable, before any work.
void check_progress(const py::object& progress);

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

/// Adds process(), read_record() and stepped_sine() with their result types.
void bind_process(py::module_& m);
/// Adds Model, build_model() and simulate().
void bind_model(py::module_& m);
/// Adds update_linear().
void bind_linear(py::module_& m);
/// Adds update_iwan() and compare().
void bind_iwan(py::module_& m);
/// Adds run().
void bind_run(py::module_& m);

}  // namespace jointlab::python
