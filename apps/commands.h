// The jointlab command's subcommands. Each registers itself on the CLI11 app
// and runs library code; no numerics live in apps/.
#pragma once

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

namespace jointlab::apps {

/// Reads `text` as a finite double into v: "" when it is one, else what is wrong with it
/// ("1e400 overflows a double (largest 1.8e+308)", "nan is not a finite number").
inline std::string finite_number(const std::string& text, double& v) {
  char* end = nullptr;
  errno = 0;
  v = std::strtod(text.c_str(), &end);
  const bool range = errno == ERANGE;
  if (text.empty() || end != text.c_str() + text.size() || std::isspace(text.front()) != 0)
    return fmt::format("{} is not a number", text);
  if (range && std::isinf(v)) {
    return fmt::format("{} overflows a double (largest {:.2g})", text,
                       std::numeric_limits<double>::max());
  }
  if (range && v == 0) {
    return fmt::format("{} underflows to 0 in a double (smallest {:.2g})", text,
                       std::numeric_limits<double>::denorm_min());
  }
  if (!std::isfinite(v)) return fmt::format("{} is not a finite number", text);
  return {};
}

/// Option check: a finite number (each value of a LO:HI range), refused naming the
/// overflow, underflow to 0 or non-finite value.
inline CLI::Validator finite() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double v = 0;
        return finite_number(text, v);
      },
      "finite");
}

/// Option check: a number in [lo, hi], refused as "V is not between LO and HI" (readable
/// bounds, unlike CLI::Range's fixed six decimals and 309-digit maximum).
inline CLI::Validator in_range(double lo, double hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) -> std::string {
        double v = 0;
        if (std::string why = finite_number(text, v); !why.empty()) return why;
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
        if (std::string why = finite_number(text, v); !why.empty()) return why;
        if (!(v > 0)) return fmt::format("{} is not a positive number", text);
        return {};
      },
      "> 0");
}

/// Option check: a number >= 0 (and finite).
inline CLI::Validator non_negative() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double v = 0;
        if (std::string why = finite_number(text, v); !why.empty()) return why;
        if (!(v >= 0)) return fmt::format("{} is negative", text);
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

/// Registers `compare`: model backbones over measured ones (compare_command.cc).
void add_compare_command(CLI::App& app);

/// `jointlab run`: a test campaign from hammer-test files to the report.
void add_run_command(CLI::App& app);

}  // namespace jointlab::apps
