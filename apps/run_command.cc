// `jointlab run CAMPAIGN --out DIR`: a whole test campaign, from hammer-test files to the
// report (campaign/campaign_run.h).
#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <CLI/CLI.hpp>

#include "jointlab/apps/commands.h"
#include "jointlab/apps/print.h"
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
      say(stderr, "[{:6.1f} s] {}\n", t, s);
    };
  }
  const campaign::RunSummary s = campaign::run_campaign(c, o);
  say(stdout, "jointlab run: {}\n", s.report());
  // One line for what went wrong, however many hits and modes: the report has the rest.
  std::vector<std::string> wrong;
  if (!s.failed_hits.empty()) {
    const campaign::FailedHit& first = s.failed_hits.front();
    // At most 240 characters of the first reason, cut after a word; the report has it whole.
    constexpr size_t kShown = 240;
    std::string why = first.why;
    if (why.size() > kShown) {
      const size_t space = why.rfind(' ', kShown - 4);
      why = why.substr(0, space == std::string::npos ? kShown - 4 : space) + " ...";
    }
    wrong.push_back(fmt::format("{} hit(s) could not be processed and are left out (first: {}: {})",
                                s.failed_hits.size(), first.file.string(), why));
  }
  if (!s.no_backbone.empty())
    wrong.push_back(fmt::format("no backbone in any hit for {}", fmt::join(s.no_backbone, ", ")));
  if (!s.refused.empty())
    wrong.push_back(fmt::format("{} refused its data", fmt::join(s.refused, " and ")));
  if (!s.stopped.empty()) {
    // "update.iwan: not run: <why>": the step and the first clause; the report has the rest.
    for (const std::string& why : s.stopped) wrong.push_back(why.substr(0, why.find(" (")));
  }
  if (!wrong.empty()) {
    throw InputError(fmt::format("{}: {}; everything else is written, the report says why: {}",
                                 args.campaign, fmt::join(wrong, ", and "),
                                 s.report_markdown.string()));
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
      "program version are unchanged. A hit that cannot be read or processed is left out and\n"
      "named (report, stderr, exit status 2); everything else is still written.\n\n"
      "Example:\n"
      "  jointlab run data/examples/riveted-campaign/campaign.toml --out out/campaign");
  cmd->add_option("CAMPAIGN", args->campaign, "campaign file (TOML)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", args->out, "output directory (created if missing)")->required();
  cmd->add_flag("--force", args->force, "recompute everything, even up-to-date outputs");
  cmd->add_option("--threads", args->threads, "workers for processing hits (default 0: every core)")
      ->check(in_range(0, 1024));
  cmd->add_flag("--quiet", args->quiet, "no progress messages on stderr");
  cmd->callback([args] { run_run(*args); });
}

}  // namespace jointlab::apps
