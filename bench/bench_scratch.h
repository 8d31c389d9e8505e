// The scratch folder of a benchmark program and the main() that removes it at the end.
#pragma once

#include <filesystem>
#include <string>
#include <system_error>

#include <unistd.h>

#include <benchmark/benchmark.h>

namespace jointlab::bench {

/// The program's own scratch folder, <temp>/jointlab-bench-<name>-<pid> (not created here).
inline std::filesystem::path scratch_dir(const std::string& name) {
  return std::filesystem::temp_directory_path() /
         ("jointlab-bench-" + name + "-" + std::to_string(getpid()));
}

/// Runs the benchmarks the command line selects, then removes `scratch`; 1 on an argument
/// Google Benchmark does not know.
inline int run_benchmarks(int argc, char** argv, const std::filesystem::path& scratch) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  std::error_code ec;
  std::filesystem::remove_all(scratch, ec);
  return 0;
}

}  // namespace jointlab::bench
