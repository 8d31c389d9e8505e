// The jointlab command's subcommands. Each registers itself on the CLI11 app
// and runs library code; no numerics live in apps/.
#pragma once

#include <CLI/CLI.hpp>

namespace jointlab::apps {

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
