// Craig–Bampton reduction of the riveted beam: building the shell model, then reducing it
// (one CHOLMOD factorisation of K_ii, shift-invert Lanczos for the fixed-interface modes,
// constraint modes from the same factor). Compares the coarse (5 mm, ~8 500 DOFs) and the
// default (2.5 mm, ~29 000 DOFs) meshes; the default must stay well under a minute.
// Run: build/bin/jointlab_bench_hcb
#include <benchmark/benchmark.h>

#include "jointlab/model/fe/model_builder.h"
#include "jointlab/model/fe/riveted_beam.h"

namespace {

using jointlab::model::fe::build_reduced_model;
using jointlab::model::fe::default_riveted_beam;
using jointlab::model::fe::RivetedBeamDescription;

void BM_BuildAndReduce(benchmark::State& state) {
  RivetedBeamDescription d = default_riveted_beam();
  d.element_size = state.range(0) * 1e-4;  // argument in 0.1 mm
  d.coupling_radius = d.element_size > 0.003 ? 0.007 : 0.004;
  for (auto _ : state) {
    const auto m = build_reduced_model(d, {});
    benchmark::DoNotOptimize(m.stiffness.nonZeros());
    state.counters["full_dofs"] = m.summary.full_dofs;
    state.counters["reduced_dofs"] = static_cast<double>(m.stiffness.rows());
  }
}
BENCHMARK(BM_BuildAndReduce)->Arg(50)->Arg(25)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
