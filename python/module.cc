// The `jointlab` Python module: the library's process, stepped-sine, record reading, build-model,
// modes, QSMA, simulate, update-linear, update-iwan, compare and run with numpy arrays in and out
// (docs/python.md), the same options and defaults as the command line, and the command line's
// one-line messages as jointlab.InputError (a ValueError). Argument conversion only: every number
// comes from the library the program uses (style.md 13).
#include <glog/logging.h>

#include "binding.h"

#include "jointlab/campaign/steps/stamp.h"

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

  bind_process(m);
  bind_model(m);
  bind_linear(m);
  bind_iwan(m);
  bind_run(m);
}
