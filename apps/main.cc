// jointlab: amplitude-dependent frequency and damping of jointed structures,
// from hammer tests and from reduced FE models with Iwan joints.
#include <cstdio>
#include <exception>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "jointlab/apps/commands.h"
#include "jointlab/core/error.h"

int main(int argc, char** argv) {
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
  jointlab::apps::add_run_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const jointlab::InputError& e) {
    fmt::print(stderr, "jointlab: error: {}\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    fmt::print(stderr, "jointlab: internal error: {}\n", e.what());
    return 3;
  }
  return 0;
}
