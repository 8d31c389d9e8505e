// `jointlab run CAMPAIGN --out DIR`: a whole test campaign, from hammer-test files to the
// report (campaign/campaign_run.h).
#include <chrono>
#include <memory>
#include <string>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <CLI/CLI.hpp>

#include "jointlab/apps/commands.h"
#include "jointlab/campaign/campaign.h"
#include "jointlab/campaign/campaign_run.h"
#include "jointlab/core/error.h"

namespace jointlab::apps {
namespace {

struct RunArgs {
  std::string campaign;
  std::string out;
  bool force = false;
  bool quiet = false;
  unsigned threads = 0;
};

void run_run(const RunArgs& args) {
  const auto t0 = std::chrono::steady_clock::now();
  const campaign::Campaign c = campaign::read_campaign(args.campaign);
  campaign::RunOptions o;
  o.out = args.out;
  o.force = args.force;
  o.threads = args.threads;
  if (!args.quiet) {
    o.progress = [&](const std::string& s) {
      const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      fmt::print(stderr, "[{:6.1f} s] {}\n", t, s);
    };
  }
  const campaign::RunSummary s = campaign::run_campaign(c, o);
  fmt::print("jointlab run: {}\n", s.report());
  if (!s.no_backbone.empty()) {
    throw InputError(
        fmt::format("{}: no backbone in any hit for {}; everything else is written, "
                    "the report says why: {}",
                    args.campaign, fmt::join(s.no_backbone, ", "), s.report_markdown.string()));
  }
}

}  // namespace

void add_run_command(CLI::App& app) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand(
      "run",
      "Run a test campaign (TOML; see docs/campaign-file.md): build or read the model, process\n"
      "every hit, summarise the scatter between hits per mode (log-amplitude bins, mean,\n"
      "standard deviation, Student-t interval, flagged hits), run QSMA of the model's modes\n"
      "and the updates, draw the figures and write OUT/report.html and OUT/report.md.\n"
      "Restartable: the model and hits are reused while their input files, settings and the\n"
      "program version are unchanged.\n\n"
      "Example:\n"
      "  jointlab run data/examples/riveted-campaign/campaign.toml --out out/campaign");
  cmd->add_option("CAMPAIGN", args->campaign, "campaign file (TOML)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", args->out, "output directory (created if missing)")->required();
  cmd->add_flag("--force", args->force, "recompute everything, even up-to-date outputs");
  cmd->add_option("--threads", args->threads, "workers for processing hits (default: every core)");
  cmd->add_flag("--quiet", args->quiet, "no progress messages on stderr");
  cmd->callback([args] { run_run(*args); });
}

}  // namespace jointlab::apps
