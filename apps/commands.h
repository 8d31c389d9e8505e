// The jointlab command's subcommands. Each registers itself on the CLI11 app
// and runs library code; no numerics live in apps/.
#pragma once

#include <limits>
#include <string>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

namespace jointlab::apps {

/// Option check: a number in [lo, hi], refused as "V is not between LO and HI" (readable
/// bounds, unlike CLI::Range's fixed six decimals and 309-digit maximum).
inline CLI::Validator in_range(double lo, double hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(text, v)) return fmt::format("{} is not a number", text);
        if (!(v >= lo && v <= hi))
          return fmt::format("{} is not between {:g} and {:g}", text, lo, hi);
        return {};
      },
      fmt::format("in [{:g}, {:g}]", lo, hi));
}

/// Option check: a number > 0 (and finite).
inline CLI::Validator positive() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(text, v)) return fmt::format("{} is not a number", text);
        if (!(v > 0 && v <= std::numeric_limits<double>::max()))
          return fmt::format("{} is not a positive number", text);
        return {};
      },
      "> 0");
}

/// Option check: a number >= 0 (and finite).
inline CLI::Validator non_negative() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(text, v)) return fmt::format("{} is not a number", text);
        if (!(v >= 0 && v <= std::numeric_limits<double>::max()))
          return fmt::format("{} is negative or not finite", text);
        return {};
      },
      ">= 0");
}

/// `jointlab process`: ring-down files -> frequency and damping versus amplitude.
void add_process_command(CLI::App& app);

/// `jointlab stepped-sine`: stepped-sine sweeps -> one backbone point per level.
void add_stepped_sine_command(CLI::App& app);

/// `jointlab build-model`: riveted beam description -> reduced (Craig-Bampton) model directory.
void add_build_model_command(CLI::App& app);

/// `jointlab modes`: linear modes of a model file, joints at linear stiffness.
void add_modes_command(CLI::App& app);

/// `jointlab qsma`: Quasi-Static Modal Analysis of one elastic mode of a model file.
void add_qsma_command(CLI::App& app);

/// `jointlab simulate`: impact ring-down of a model with Iwan joints, written as a test file.
void add_simulate_command(CLI::App& app);

/// `jointlab update-linear` and `jointlab update-iwan`: model updating against process output.
void add_update_commands(CLI::App& app);

/// `jointlab run`: a test campaign from hammer-test files to the report.
void add_run_command(CLI::App& app);

}  // namespace jointlab::apps
