// Model, build_model() and simulate(): the model side (docs/python.md).
#include "binding.h"

#include <cstdint>
#include <limits>

#include <fmt/format.h>

#include "jointlab/data/record_writer.h"
#include "jointlab/model/fe/model_builder.h"
#include "jointlab/model/fe/riveted_beam.h"
#include "jointlab/model/joint_condensation.h"
#include "jointlab/model/linear_modes.h"
#include "jointlab/model/qsma.h"
#include "jointlab/model/qsma_output.h"
#include "jointlab/model/sim/ringdown_simulation.h"
#include "jointlab/model/sim/simulated_record.h"

namespace jointlab::python {
namespace {

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

// simulate's `model` where it is no jointlab.Model: the model file's path.
std::string model_file(const py::object& model_arg) {
  try {
    return text(model_arg.cast<PathArg>());
  } catch (const py::cast_error&) {
    throw py::type_error(
        fmt::format("model: expected a model file (str or os.PathLike) or a jointlab.Model; got {}",
                    Py_TYPE(model_arg.ptr())->tp_name));
  }
}

// --sensors as text, as the command reads them: one DOF or a list of them (none: empty).
std::vector<std::string> sensor_texts(const py::object& sensors_arg) {
  std::vector<std::string> sensors;
  if (py::isinstance<py::str>(sensors_arg) || is_integer(sensors_arg)) {
    sensors.push_back(dof_text(sensors_arg, "--sensors"));
  } else if (py::isinstance<py::iterable>(sensors_arg)) {
    for (const py::handle h : sensors_arg) sensors.push_back(dof_text(h, "--sensors"));
  } else if (!sensors_arg.is_none()) {
    sensors.push_back(dof_text(sensors_arg, "--sensors"));  // says what is expected
  }
  return sensors;
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
  const std::string model_name = given ? given->path() : model_file(model_arg);
  const std::string impact_dof = dof_text(impact, "--impact");
  const std::vector<std::string> sensors = sensor_texts(sensors_arg);
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

}  // namespace

void bind_model(py::module_& m) {
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
}

}  // namespace jointlab::python
