// Benchmark of the ring-down pipeline on a realistic record: 8 channels, 3 bands,
// fs 5120 Hz, 6 s (the shape of issue 2's acceptance record), single threaded.
// It times process_record (spectra, continuation, band analytic signals, local
// fits) on a record already in memory; file reading is not included, as in the
// SciPy baseline (bench/scipy_baseline.py) it is compared with.
#include <benchmark/benchmark.h>

#include <cstdlib>

#include "jointlab/data/read_record.h"
#include "jointlab/data/record.h"
#include "jointlab/modal/process.h"
#include "jointlab/tests/synthetic.h"

namespace {

jointlab::data::Record make_record() {
  jointlab::data::Record rec;
  rec.source = "bench.csv";
  rec.fs = 5120.0;
  for (int c = 0; c < 8; ++c) {
    const auto r = jointlab::testing::three_mode_record(60.0, 6.0, 1e-3, 100 + c);
    jointlab::data::Channel ch;
    ch.name = "acc" + std::to_string(c + 1);
    ch.quantity = jointlab::Quantity::kAcceleration;
    ch.samples = r.acceleration;
    rec.channels.push_back(ch);
  }
  return rec;
}

// Times process_record on `rec` in the bands of the three modes of
// three_mode_record(60 Hz): 60, 162 and 366 Hz, with `threads` channel workers.
void time_process(benchmark::State& state, const jointlab::data::Record& rec, unsigned threads) {
  jointlab::modal::ProcessOptions opt;
  opt.bands = {{48, 72}, {140, 185}, {320, 410}};
  opt.threads = threads;
  jointlab::signal::FftCache cache;
  for (auto _ : state) {
    auto result = jointlab::modal::process_record(rec, opt, cache);
    benchmark::DoNotOptimize(result);
  }
}

void BM_ProcessRecord(benchmark::State& state) {
  time_process(state, make_record(), 1);
  state.SetLabel("8 channels x 3 bands, 30720 samples");
}
BENCHMARK(BM_ProcessRecord)->Unit(benchmark::kMillisecond);

// The same on a record read from $JOINTLAB_BENCH_RECORD (bench/compare_scipy.sh
// writes one and times the SciPy baseline on it too); skipped when unset. The argument
// is the number of channel workers: 1 (as the single-threaded baseline) and 2.
void BM_ProcessFile(benchmark::State& state) {
  const char* path = std::getenv("JOINTLAB_BENCH_RECORD");
  if (!path) {
    state.SkipWithError("JOINTLAB_BENCH_RECORD not set");
    return;
  }
  time_process(state, jointlab::data::read_record(path), static_cast<unsigned>(state.range(0)));
}
BENCHMARK(BM_ProcessFile)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
