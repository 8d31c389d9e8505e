// jointlab: amplitude-dependent frequency and damping of jointed structures,
// from hammer tests and from reduced FE models with Iwan joints.
#include <algorithm>
#include <cstdio>
#include <exception>
#include <new>
#include <string>

#include <fmt/format.h>
#include <glog/logging.h>
#include <CLI/CLI.hpp>

#include "jointlab/apps/commands.h"
#include "jointlab/apps/print.h"
#include "jointlab/core/error.h"
#include "jointlab/core/text.h"

int main(int argc, char** argv) {
  // Ceres logs through glog; the optimisers' outcomes reach the user through their summaries,
  // so its own lines (a rejected trial point, "Logging before InitGoogleLogging") stay out of
  // the program's stderr.
  FLAGS_minloglevel = google::GLOG_FATAL;
  google::InitGoogleLogging(argc > 0 ? argv[0] : "jointlab");
  CLI::App app{
      "jointlab: amplitude-dependent natural frequency and damping of jointed structures.\n"
      "Test side: 'process' turns impact ring-downs into backbones (frequency and damping\n"
      "versus amplitude). Model side: reduced FE models with Iwan joints and QSMA.\n"
      "Every quantity is SI (m, m/s, m/s^2, N, s, Hz); damping ratios are fractions.\n"
      "Run 'jointlab <command> --help' for each command."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "jointlab 0.1.0");
  jointlab::apps::add_process_command(app);
  jointlab::apps::add_stepped_sine_command(app);
  jointlab::apps::add_build_model_command(app);
  jointlab::apps::add_modes_command(app);
  jointlab::apps::add_qsma_command(app);
  jointlab::apps::add_simulate_command(app);
  jointlab::apps::add_update_commands(app);
  jointlab::apps::add_compare_command(app);
  jointlab::apps::add_run_command(app);
  // A mistyped command name would otherwise be reported as a missing one.
  bool known = argc < 2 || argv[1][0] == '-';
  std::string names;
  for (const CLI::App* sub : app.get_subcommands({})) {
    known = known || sub->check_name(argv[1]);
    names += (names.empty() ? "" : ", ") + sub->get_name();
  }
  if (!known) {
    jointlab::apps::say(stderr, "jointlab: error: unknown command '{}' (commands: {})\n",
                        jointlab::shorten(argv[1]), names);
    return 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version exit 0 as CLI11 prints them; an argument error is one line, status 2.
    if (e.get_exit_code() == 0) return app.exit(e);
    std::string message = e.what();
    std::replace(message.begin(), message.end(), '\n', ' ');
    jointlab::apps::say(stderr, "jointlab: error: {} (see --help)\n",
                        jointlab::shorten(message, 400));
    return 2;
  } catch (const jointlab::InputError& e) {
    // Readers cut names in their messages; this bounds whatever else a message quotes.
    jointlab::apps::say(stderr, "jointlab: error: {}\n", jointlab::shorten(e.what(), 2000));
    return 2;
  } catch (const std::bad_alloc&) {
    jointlab::apps::say(stderr, "jointlab: error: out of memory\n");
    return 2;
  } catch (const std::exception& e) {
    jointlab::apps::say(stderr, "jointlab: internal error: {}\n",
                        jointlab::shorten(e.what(), 2000));
    return 3;
  }
  return 0;
}
