// `jointlab stepped-sine`: stepped-sine sweeps -> one backbone point per level.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "jointlab/apps/commands.h"
#include "jointlab/apps/print.h"
#include "jointlab/apps/stepped_sine_figure.h"
#include "jointlab/core/error.h"
#include "jointlab/core/units.h"
#include "jointlab/correlate/measured_data.h"
#include "jointlab/data/names.h"
#include "jointlab/data/process_folder.h"
#include "jointlab/data/stepped_sine.h"
#include "jointlab/modal/stepped_sine.h"
#include "jointlab/modal/stepped_sine_output.h"

namespace jointlab::apps {

namespace {

struct SteppedSineArgs {
  std::vector<std::string> files;
  std::string amplitude = "velocity";
  std::string quantity;
  std::string damping = "hysteretic";
  int residual_terms = modal::SteppedSineOptions{}.residual_terms;
  double coverage_factor = modal::SteppedSineOptions{}.coverage_factor;
  std::vector<std::string> ringdowns;
  std::string figure;
  std::string out;
};

// The figure's series: each file's response- and force-controlled points, then the
// ring-down backbones.
std::vector<FigureSeries> figure_series(const std::vector<modal::SteppedSineFileResult>& results,
                                        const std::vector<correlate::MeasuredBackbone>& ring,
                                        const std::vector<std::string>& ring_files) {
  namespace fs = std::filesystem;
  std::vector<FigureSeries> out;
  for (const auto& r : results) {
    for (const auto control : {data::SineControl::kResponse, data::SineControl::kForce}) {
      std::vector<size_t> rows;
      for (size_t i = 0; i < r.points.size(); ++i) {
        if (r.points[i].status == modal::SineStatus::kOk && r.tables[i].control == control) {
          rows.push_back(i);
        }
      }
      if (rows.empty()) continue;
      FigureSeries s;
      s.label = results.size() > 1
                    ? fmt::format("{}: {} control", fs::path(r.source).stem().string(),
                                  data::control_name(control))
                    : fmt::format("stepped sine, {} control", data::control_name(control));
      const auto n = static_cast<Eigen::Index>(rows.size());
      s.amplitude.resize(n), s.frequency_hz.resize(n), s.damping.resize(n);
      s.frequency_std_hz.resize(n), s.damping_std.resize(n);
      for (Eigen::Index k = 0; k < n; ++k) {
        const modal::SineBackbonePoint& p = r.points[rows[static_cast<size_t>(k)]];
        s.amplitude(k) = p.amplitude, s.frequency_hz(k) = p.frequency_hz;
        s.damping(k) = p.damping_ratio, s.frequency_std_hz(k) = p.frequency_std_hz;
        s.damping_std(k) = p.damping_std;
      }
      out.push_back(std::move(s));
    }
  }
  for (size_t i = 0; i < ring.size(); ++i) {
    FigureSeries s;
    s.label = "ring-down " + fs::path(ring_files[i]).stem().string();
    s.amplitude = ring[i].amplitude, s.frequency_hz = ring[i].frequency_hz;
    s.damping = ring[i].damping_ratio, s.frequency_std_hz = ring[i].frequency_std_hz;
    s.damping_std = ring[i].damping_std;
    s.points = false;
    out.push_back(std::move(s));
  }
  return out;
}

void run_stepped_sine(const SteppedSineArgs& args) {
  modal::SteppedSineOptions opt;
  opt.amplitude = motion_quantity("--amplitude", args.amplitude);
  opt.damping =
      args.damping == "viscous" ? modal::SineDamping::kViscous : modal::SineDamping::kHysteretic;
  opt.residual_terms = args.residual_terms;
  opt.coverage_factor = args.coverage_factor;
  if (const std::string why = opt.check(); !why.empty()) throw InputError(why);
  std::optional<Quantity> quantity;
  if (!args.quantity.empty()) quantity = motion_quantity("--quantity", args.quantity);

  namespace fs = std::filesystem;
  data::check_distinct_stems(args.files);
  // Read and extract everything first: a bad file stops the run before any output exists.
  std::vector<correlate::MeasuredBackbone> ring;
  for (const std::string& f : args.ringdowns)
    ring.push_back(correlate::measured_backbone(data::read_process_backbone(f), 0));
  if (!args.figure.empty()) {
    const std::string ext = fs::path(args.figure).extension().string();
    if (ext != ".png" && ext != ".svg" && ext != ".pdf") {
      throw InputError(
          fmt::format("--figure {}: the extension must be .png, .svg or .pdf", args.figure));
    }
  }
  std::vector<modal::SteppedSineFileResult> results;
  for (const std::string& f : args.files) {
    modal::SteppedSineFileResult r = modal::extract_stepped_sine_file(f, quantity, opt);
    r.source = f;
    for (size_t i = 0; i < r.tables.size(); ++i)
      say(stderr, "{} {}: {}\n", f, r.tables[i].label, r.points[i].report());
    results.push_back(std::move(r));
  }
  const fs::path out(args.out);
  std::error_code ec;
  fs::create_directories(out, ec);
  if (!fs::is_directory(out))
    throw InputError(where(args.out, 0, "cannot create output directory"));
  int written = 0;
  for (const auto& r : results) {
    modal::write_sine_backbone(out, r);
    written += modal::usable_points(r) > 0;
  }
  modal::write_sine_summary(out, results, opt);
  if (!args.figure.empty()) {
    plot_sine_figure(
        figure_series(results, ring, args.ringdowns),
        "stepped sine (points, k sigma bars) and ring-down backbones",
        fmt::format("{} amplitude [{}]", quantity_name(opt.amplitude), si_unit(opt.amplitude)),
        args.figure);
  }
  say(stdout, "jointlab stepped-sine: {} backbone file(s) and summary.json written to {}\n",
      written, out.string());
  // As process: no backbone at all fails the command (summary.json says why per file).
  if (written == 0) {
    throw InputError(fmt::format(
        "stepped-sine: no backbone from any of the {} file(s): no point is usable (their "
        "reasons are above and in {}/summary.json)",
        results.size(), out.string()));
  }
}

}  // namespace

void add_stepped_sine_command(CLI::App& app) {
  auto args = std::make_shared<SteppedSineArgs>();
  CLI::App* cmd = app.add_subcommand(
      "stepped-sine",
      "Turn stepped-sine sweeps into backbone points: one per level.\n\n"
      "Each FILE holds one or more sweeps (levels) around one mode: frequency, force and\n"
      "response amplitudes and the response's phase relative to the force (CSV, see\n"
      "docs/stepped-sine-table.md, or the .mat struct layout of the Brake-Reuss data).\n"
      "Response-controlled sweeps hold the response amplitude, so the structure is\n"
      "quasi-linear at that level: a single-mode FRF\n"
      "  H(w) = Q / (w_n^2 - w^2 + 2 i zeta w_n^2) + R0 + R1 (w - w_c)/w_c\n"
      "is fitted (Ceres) and its f_n and zeta, with uncertainties from the fit, are the point,\n"
      "at the response amplitude at f_n. Force-controlled sweeps give their phase resonance\n"
      "(response in quadrature with the force, interpolated between steps) and the damping\n"
      "of the energy balance there, zeta = |Q| F / (2 w^2 X), with the modal constant |Q| of\n"
      "the file's response-controlled levels (or of the sweep's own fit when it has none) --\n"
      "less direct, flagged as such (damping_direct 0). Uncertainties are k*sigma.\n"
      "A sweep that holds acceleration (or velocity) lets the displacement vary as w^-2 (w^-1):\n"
      "zeta then comes out as zeta / (1 + s), s = dln k1/dln A < 0 for softening joints\n"
      "(docs/stepped-sine.md).\n"
      "Writes OUT/<file stem>.backbone.csv (columns amplitude, frequency_hz, damping_ratio,\n"
      "frequency_std_hz, damping_std as 'process' writes them, then level,\n"
      "response_controlled, points, fit_rms, displacement_m, force_n, damping_direct) and\n"
      "OUT/summary.json.\n\n"
      "Example:\n"
      "  jointlab stepped-sine data/examples/brake-reuss-beam/forced_frequency_responses.mat \\\n"
      "      --out sine\n"
      "  jointlab stepped-sine sweep20.csv sweep40.csv --amplitude displacement --out sine");
  cmd->option_defaults()->always_capture_default();
  cmd->add_option("FILE", args->files,
                  "stepped-sine files: CSV (docs/stepped-sine-table.md) or .mat")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option(
      "--amplitude", args->amplitude,
      "amplitude column: velocity (default, m/s), displacement (m) or acceleration (m/s^2),\n"
      "each at the natural frequency");
  cmd->add_option("--quantity", args->quantity,
                  "what a response column without a [unit] measures (SI assumed): acceleration,\n"
                  "velocity or displacement; without it such a column is an error");
  cmd->add_option("--damping-model", args->damping,
                  "damping term of the fitted mode: hysteretic (default; rate-independent joint\n"
                  "friction) or viscous; both give zeta = D / (2 pi k1 A^2) at f_n")
      ->check(CLI::IsMember({"hysteretic", "viscous"}));
  cmd->add_option("--residual-terms", args->residual_terms,
                  "other modes' share in the band: 0 none, 1 a complex constant, 2 constant and\n"
                  "slope (default)")
      ->check(CLI::Range(0, 2));
  cmd->add_option("--coverage-factor", args->coverage_factor,
                  "k of the reported uncertainties k*sigma (default 3, as 'process'; 1: one sigma)")
      ->check(CLI::Range(1.0, 10.0));
  cmd->add_option("--ringdown", args->ringdowns,
                  "ring-down backbone CSVs of 'process' to draw in the figure (repeat; their\n"
                  "amplitude must be the same quantity as --amplitude)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--figure", args->figure,
                  "draw the points (with k sigma bars) and the --ringdown curves: frequency and\n"
                  "damping versus amplitude, into FILE (.png, .svg or .pdf)");
  cmd->add_option("--out", args->out, "output directory (created if missing)")->required();
  cmd->callback([args] { run_stepped_sine(*args); });
}

}  // namespace jointlab::apps
