// process(), read_record() and stepped_sine(): records in, backbones out (docs/python.md).
#include "binding.h"

#include <complex>
#include <functional>
#include <map>
#include <regex>
#include <tuple>

#include <fmt/format.h>

#include "jointlab/core/units.h"
#include "jointlab/data/names.h"
#include "jointlab/data/output_stage.h"
#include "jointlab/data/read_record.h"
#include "jointlab/modal/process.h"
#include "jointlab/modal/process_output.h"
#include "jointlab/modal/stepped_sine.h"
#include "jointlab/modal/stepped_sine_output.h"

namespace jointlab::python {
namespace {

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

py::dict read_record(const PathArg& path_arg) {
  const std::string path = text(path_arg);
  data::Record rec;
  {
    py::gil_scoped_release release;
    rec = data::read_record(path);
  }
  return record_dict(std::move(rec));
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

void bind_process(py::module_& m) {
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

}  // namespace jointlab::python
