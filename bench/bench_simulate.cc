// Impact ring-down of the riveted beam (model/sim): 2.5 mm shell model reduced to 353 DOFs,
// 24 rivets with Iwan joints in x and y (48 joint coordinates), struck at a sensor point,
// 2 s at 10 kHz with the automatic substeps. Target: a 2 s record in under 10 s. The
// 0.2 s case gives the cost per step without the tail of the run.
// Run: build/bin/jointlab_bench_simulate
#include <cstdlib>
#include <filesystem>
#include <string>

#include <benchmark/benchmark.h>

#include "jointlab/model/fe/model_builder.h"
#include "jointlab/model/fe/riveted_beam.h"
#include "jointlab/model/model_file.h"
#include "jointlab/model/sim/ringdown_simulation.h"

namespace {

namespace fs = std::filesystem;
using namespace jointlab::model;

const Model& riveted_beam() {
  static const Model model = [] {
    const fe::ReducedModel m = fe::build_reduced_model(fe::default_riveted_beam(), {});
    const fs::path dir = fs::temp_directory_path() / "jointlab_bench_simulate_model";
    fe::write_model_directory(dir, m);
    return read_model(dir / "model.toml");
  }();
  return model;
}

void BM_RivetedBeamRingdown(benchmark::State& state) {
  const Model& model = riveted_beam();
  SimulationOptions o;
  // Sensor points are the labelled nodes outside the rivets (1001..2999) and modes (0).
  for (Eigen::Index i = 0; i < model.size(); ++i) {
    const std::string& label = model.dof_labels[static_cast<size_t>(i)];
    if (std::atoi(label.c_str()) >= 3000 && label.ends_with(":3")) o.sensors.push_back(i);
  }
  o.pulse = {o.sensors.front(), 30.0, 5e-4, 0.01};
  o.fs = 10000;
  o.duration = static_cast<double>(state.range(0)) / 10;
  SimulationSummary s;
  for (auto _ : state) {
    const SimulatedResponse r = simulate_ringdown(model, o, &s);
    benchmark::DoNotOptimize(r.acceleration.data());
  }
  state.counters["steps"] = static_cast<double>(s.steps);
  state.counters["newton_per_step"] =
      static_cast<double>(s.newton_iterations) / static_cast<double>(s.steps);
  state.counters["energy_closure"] = s.energy.relative_closure();
  state.SetLabel(std::to_string(s.modes) + " modes, " + std::to_string(s.joint_coordinates) +
                 " joint coordinates, " + std::to_string(s.substeps) + " substeps");
}
BENCHMARK(BM_RivetedBeamRingdown)->Arg(2)->Arg(20)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
