// `jointlab process`: impact ring-downs -> natural frequency and damping versus amplitude.
#include <algorithm>
#include <cmath>
#include <exception>
#include <filesystem>
#include <functional>
#include <iterator>
#include <mutex>
#include <new>
#include <regex>
#include <string>
#include <tuple>
#include <unordered_map>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "jointlab/apps/commands.h"
#include "jointlab/apps/print.h"
#include "jointlab/core/error.h"
#include "jointlab/core/parallel.h"
#include "jointlab/core/text.h"
#include "jointlab/core/units.h"
#include "jointlab/data/names.h"
#include "jointlab/data/output_stage.h"
#include "jointlab/data/read_record.h"
#include "jointlab/modal/process.h"
#include "jointlab/modal/process_output.h"

namespace jointlab::apps {

namespace {

struct ProcessArgs {
  std::vector<std::string> files;
  std::vector<std::string> channels;
  std::vector<std::string> bands;
  int modes = 0;
  std::string quantity;
  std::string amplitude = "velocity";
  std::string method = "hilbert";
  std::string out;
  double snr_min = modal::RingdownOptions{}.snr_min;
  double max_damping_std = modal::RingdownOptions{}.max_damping_rel_std;
  double coverage_factor = modal::RingdownOptions{}.coverage_factor;
  double min_share = modal::ProcessOptions{}.min_share;
  unsigned threads = 0;
};

signal::Band parse_band(const std::string& text) {
  const auto colon = text.find(':');
  if (colon == std::string::npos) {
    throw InputError(fmt::format("--band {}: expected LO:HI in Hz, e.g. 70:90", text));
  }
  double lo = 0, hi = 0;
  for (const auto& [part, value, what] : {std::tuple{text.substr(0, colon), &lo, "LO"},
                                          std::tuple{text.substr(colon + 1), &hi, "HI"}}) {
    if (part.empty())
      throw InputError(fmt::format("--band {}: {} is missing; give LO:HI in Hz", text, what));
    if (std::string why = finite_number(part, *value); !why.empty()) {
      throw InputError(fmt::format("--band {}: {}; expected LO:HI in Hz, e.g. 70:90", text, why));
    }
  }
  if (!(lo > 0 && hi > lo)) {
    throw InputError(fmt::format("--band {}: need 0 < LO < HI (Hz)", text));
  }
  return {lo, hi};
}

// Names of the files `process` writes: summary.json and "<stem>.<channel>.band<k>.csv".
bool is_process_output(const std::string& name) {
  static const std::regex backbone(R"(.*\.band[0-9]+\.csv)");
  return name == "summary.json" || std::regex_match(name, backbone);
}

void run_process(const ProcessArgs& args) {
  modal::ProcessOptions opt;
  for (const std::string& b : args.bands) opt.bands.push_back(parse_band(b));
  opt.modes = args.modes;
  opt.channels = args.channels;
  if (!args.quantity.empty()) opt.quantity = motion_quantity("--quantity", args.quantity);
  opt.ringdown.amplitude = motion_quantity("--amplitude", args.amplitude);
  opt.ringdown.method = args.method == "pff" ? modal::Method::kPeaks : modal::Method::kHilbert;
  opt.ringdown.snr_min = args.snr_min;
  opt.ringdown.max_damping_rel_std = args.max_damping_std;
  opt.ringdown.coverage_factor = args.coverage_factor;
  opt.min_share = args.min_share;
  // Files first, one worker each; the threads left over go to each record's bands and channels.
  const unsigned threads = threads_or_cores(args.threads);
  opt.threads = std::max<unsigned>(
      1, threads / static_cast<unsigned>(std::min<size_t>(args.files.size(), threads)));
  if (std::string why = opt.check(); !why.empty()) throw InputError(why);

  namespace fs = std::filesystem;
  data::check_distinct_stems(args.files);
  // A channel named twice is one channel: processed once (its outputs would share a name).
  std::unordered_map<std::string, size_t> times;
  for (const std::string& c : args.channels) ++times[c];
  for (const std::string& c : args.channels) {
    size_t& n = times[c];
    if (n > 1) {
      say(stderr, "jointlab process: --channel {} is given {} times; it is processed once\n",
          shorten(c), n);
    }
    n = 0;  // said once
  }

  // Backbones and summary.json appear together, replacing the previous run's as a set.
  // Backbone-like names count as old outputs only in a folder holding an old summary.json.
  const bool old_outputs = fs::exists(fs::path(args.out) / "summary.json");
  data::OutputStage stage(
      args.out, "process",
      old_outputs ? is_process_output : std::function<bool(const std::string&)>{});
  const fs::path& out = stage.path();
  // Files are independent: one worker per core, each with its own FFT plans.
  std::vector<modal::RecordResult> results(args.files.size());
  std::mutex print;
  parallel_for(
      args.files.size(), args.threads, [] { return signal::FftCache{}; },
      [&](size_t i, signal::FftCache& cache) {
        try {
          const data::Record rec = data::read_record(args.files[i]);
          results[i] = modal::process_record(rec, opt, cache);
        } catch (const std::bad_alloc&) {
          // Named, not "internal error: std::bad_alloc": which record did not fit.
          throw InputError(data::out_of_memory_message(
              args.files[i], std::min<size_t>(args.files.size(), threads_or_cores(args.threads))));
        }
        modal::write_backbones(out, results[i], opt.ringdown);
        // A line per channel and band, written in blocks (a record may hold 1e5 channels).
        std::lock_guard<std::mutex> lock(print);
        std::string lines;
        for (const modal::LeftOutPeak& p : results[i].left_out) {
          fmt::format_to(std::back_inserter(lines), "{}: --modes: {}\n", args.files[i],
                         modal::left_out_line(p));
        }
        for (const modal::ChannelBand& r : results[i].results) {
          fmt::format_to(std::back_inserter(lines), "{} {} band {}: {}\n", args.files[i], r.channel,
                         r.band_index, r.ringdown.summary.report());
          if (lines.size() > 65536) say(stderr, "{}", std::exchange(lines, {}));
        }
        say(stderr, "{}", lines);
      });
  modal::write_summary(out, results, opt);
  stage.commit();
  size_t written = 0;
  for (const auto& r : results) {
    for (const auto& c : r.results)
      written += c.ringdown.summary.status == modal::RingdownStatus::kOk;
  }
  say(stdout, "jointlab process: {} backbone file(s) and summary.json written to {}\n", written,
      args.out);
  // Like `run`: everything is written, and a band with a backbone at no channel of any file
  // (not merely at some: nodal sensors) fails the command, naming the band and why.
  std::vector<std::string> empty;
  // --modes N where fewer than N peaks give modal data: what was found is written.
  for (const auto& r : results) {
    if (!r.shortfall.empty()) empty.push_back(r.source + ": " + r.shortfall);
  }
  size_t bands = 0;
  for (const auto& r : results) bands = std::max(bands, r.bands.size());
  for (size_t b = 0; b < bands; ++b) {
    std::string why;
    bool some = false;
    for (const auto& r : results) {
      if (b >= r.bands.size()) continue;
      const std::string w = modal::band_without_backbone(r, static_cast<int>(b) + 1);
      some = some || w.empty();
      if (why.empty() && !w.empty()) {
        why = fmt::format("band {} ({:g}:{:g} Hz): no backbone at any channel{}; {}{}", b + 1,
                          r.bands[b].lo, r.bands[b].hi, results.size() > 1 ? " of any file" : "",
                          results.size() > 1 ? r.source + " " : "", w);
      }
    }
    if (!some) empty.push_back(why);
    // A band whose reference channel has a backbone but no linear values fails the same way
    // (summary.json says why instead of writing 0 for them).
    for (const auto& r : results) {
      if (!some || b >= r.bands.size()) continue;
      for (const modal::ChannelBand& c : r.results) {
        const modal::RingdownSummary& s = c.ringdown.summary;
        if (c.band_index != static_cast<int>(b) + 1 || c.channel != r.reference[b] ||
            s.status != modal::RingdownStatus::kOk || s.has_linear())
          continue;
        empty.push_back(fmt::format("band {} ({:g}:{:g} Hz): {}{}: {}", b + 1, r.bands[b].lo,
                                    r.bands[b].hi, results.size() > 1 ? r.source + " " : "",
                                    c.channel, s.linear_reason));
      }
    }
  }
  if (!empty.empty()) {
    throw InputError(
        fmt::format("{}; everything else is written to {}", fmt::join(empty, "; "), args.out));
  }
}

}  // namespace

void add_process_command(CLI::App& app) {
  auto args = std::make_shared<ProcessArgs>();
  CLI::App* cmd = app.add_subcommand(
      "process",
      "Turn impact ring-downs into natural frequency and damping versus amplitude.\n\n"
      "For every FILE, every selected channel and every band, the mode's ring-down is\n"
      "band-passed (zero phase), converted to displacement, Hilbert-transformed, and\n"
      "its phase and log-envelope are fitted locally and differentiated:\n"
      "  omega_d = dtheta/dt, sigma = -dlnA/dt, f_n = sqrt(omega_d^2 + sigma^2)/2pi,\n"
      "  zeta = sigma/omega_n, each with an expanded uncertainty k*sigma (coverage factor\n"
      "  k = 3 by default, --coverage-factor).\n"
      "Only the span well above the noise floor and clear of the impact is kept; a\n"
      "clipped channel (samples pinned at its range) is read after its last pinned sample.\n"
      "Writes OUT/<file stem>.<channel>.band<k>.csv and OUT/summary.json.\n\n"
      "Example:\n"
      "  jointlab process hit1.csv hit2.csv --band 70:90 --band 280:320 --out results\n"
      "  jointlab process hit1.csv --modes 3 --channel acc1 --amplitude displacement --out r");
  cmd->option_defaults()->always_capture_default();
  cmd->add_option("FILE", args->files,
                  "test files: CSV (see docs/csv.md), UFF 58 (.uff), MATLAB (.mat)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--channel", args->channels,
                  "channel to process (repeat; default: all but forces)");
  auto* band = cmd->add_option("--band", args->bands, "band LO:HI in Hz around one mode (repeat)");
  auto* modes =
      cmd->add_option("--modes", args->modes, "use the N strongest spectral peaks as bands instead")
          ->check(positive());
  band->excludes(modes);
  cmd->add_option("--quantity", args->quantity,
                  "what channels without a [unit] measure: acceleration, velocity or\n"
                  "displacement (SI units assumed); required when a channel has no unit");
  cmd->add_option(
      "--amplitude", args->amplitude,
      "amplitude column: velocity (default, m/s), displacement (m) or acceleration (m/s^2)");
  cmd->add_option("--method", args->method,
                  "hilbert (default) or pff (peak finding and fitting, an independent cross-check)")
      ->check(CLI::IsMember({"hilbert", "pff"}));
  cmd->add_option("--snr-min", args->snr_min,
                  "keep points whose envelope is at least this many times the noise floor")
      ->check(in_range(1.0, 1e6));
  cmd->add_option(
         "--max-damping-std", args->max_damping_std,
         "drop points whose one-sigma damping uncertainty exceeds this fraction of the damping")
      ->check(in_range(1e-6, 10.0));
  cmd->add_option(
         "--coverage-factor", args->coverage_factor,
         "k of the reported uncertainties k*sigma (1: one sigma; 3 makes one record's\n"
         "uncertainties cover at least 90 % of its points, where its errors move together)")
      ->check(in_range(1.0, 10.0));
  cmd->add_option("--min-share", args->min_share,
                  "give no backbone from a channel that sees a band's mode at less than this\n"
                  "fraction of the strongest channel's amplitude (near a node its damping would\n"
                  "follow the mode shape's change); 0 keeps every channel")
      ->check(in_range(0.0, 0.99));
  cmd->add_option(
         "--threads", args->threads,
         "worker threads, shared out over the files and then each file's bands and channels\n"
         "(default 0: every core); the results do not depend on it")
      ->check(in_range(0, 1024));
  cmd->add_option("--out", args->out, "output directory (created if missing)")->required();
  cmd->callback([args] {
    if (args->bands.empty() && args->modes == 0) {
      throw InputError("process: give --band LO:HI (repeatable) or --modes N");
    }
    run_process(*args);
  });
}

}  // namespace jointlab::apps
