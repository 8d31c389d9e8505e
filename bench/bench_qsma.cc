// `jointlab qsma` on a 582-DOF, 48-rivet reduced riveted beam against a Newton on all DOFs
// for the same load levels, both in one run.
//
// Run: build/bin/jointlab_bench_qsma
//
// Model (built once, into a temporary folder): the example description
// (examples/riveted_beam/description.toml) with 48 rivets, the beam mesh and one
// fixed-interface mode: 581 boundary DOFs + 1 mode = 582 DOFs, 96 Iwan coordinates (x and
// y of every rivet), six rigid-body modes.
// Command: what `jointlab qsma MODEL --mode 1 --points 21` does, file to file: read the
// model file and its matrices, the lowest modes by shift-invert Lanczos on CHOLMOD, the
// condensation C = B G B^T (one sparse Cholesky), the default-range curve (microslip
// start, end at full macroslip of the joints carrying the mode's slip or at the limit
// load, every search and bracketing solve included) and the CSV written.
// All DOFs: the same 21 load levels (given to it: no range search), each solved by Newton
// on K_lin u - B^T h(B u) = alpha M phi with Phi_rb^T M u = 0 (Lagrange multipliers), a
// dense LU of the bordered tangent and a line search on the potential, continued from the
// previous level (tests/all_dof_newton.h, the reference the tests use; what a NumPy
// script does).
// BM_QsmaSpeedup times both once per iteration and reports the ratio.
#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "jointlab/bench/bench_scratch.h"
#include "jointlab/model/fe/model_builder.h"
#include "jointlab/model/fe/riveted_beam.h"
#include "jointlab/model/joint_condensation.h"
#include "jointlab/model/model_file.h"
#include "jointlab/model/qsma.h"
#include "jointlab/model/qsma_output.h"
#include "jointlab/tests/all_dof_newton.h"

namespace {

namespace fs = std::filesystem;
using namespace jointlab;

constexpr int kPoints = 21;

fs::path work_dir() {
  static const fs::path dir = bench::scratch_dir("qsma");
  return dir;
}

// The example description with 48 rivets, the beam mesh and one fixed-interface mode.
fs::path model_file() {
  static const fs::path path = [] {
    std::ifstream in(fs::path(JOINTLAB_SOURCE_DIR) / "examples/riveted_beam/description.toml");
    std::stringstream text;
    text << in.rdbuf();
    std::string s = text.str();
    const auto replace = [&](const std::string& from, const std::string& to) {
      const size_t at = s.find(from);
      if (at == std::string::npos) throw std::runtime_error("description lacks " + from);
      s.replace(at, from.size(), to);
    };
    replace("element = \"shell\"", "element = \"beam\"");
    replace("count = 24", "count = 48");
    replace("fixed_interface_modes = 60", "fixed_interface_modes = 1");
    fs::create_directories(work_dir());
    const fs::path description = work_dir() / "description.toml";
    std::ofstream(description) << s;
    const model::fe::ReducedModel reduced =
        model::fe::build_reduced_model(model::fe::read_riveted_beam_description(description), {});
    model::fe::write_model_directory(work_dir() / "model", reduced);
    return work_dir() / "model" / "model.toml";
  }();
  return path;
}

// `jointlab qsma MODEL --mode 1 --points 21 --out FILE`, in process; returns the curve.
std::vector<model::QsmaPoint> qsma_command() {
  const model::Model m = model::read_model(model_file());
  model::ModesOptions modes;
  modes.elastic_count = 1;
  const model::JointCondensation condensed(m, modes);
  model::QsmaOptions options;
  options.points = kPoints;
  model::QsmaSummary summary;
  std::vector<model::QsmaPoint> curve = model::qsma(condensed, 1, options, &summary);
  model::write_qsma_csv(work_dir() / "qsma.csv", curve);
  return curve;
}

// The reference's set-up (outside the timing): the model, its modes, the load levels.
struct Reference {
  model::Model model;
  model::LinearModes modes;
  std::vector<double> alphas;
};
const Reference& reference() {
  static const Reference r = [] {
    Reference out;
    out.model = model::read_model(model_file());
    out.modes = model::linear_modes(out.model);
    for (const model::QsmaPoint& p : qsma_command()) out.alphas.push_back(p.force_amplitude);
    return out;
  }();
  return r;
}

double all_dof_curve() {
  const Reference& r = reference();
  testing::AllDofNewton newton(r.model, r.modes, r.modes.rigid_count);
  const int converged = newton.run(r.alphas);
  if (converged != static_cast<int>(r.alphas.size())) {
    throw std::runtime_error("the all-DOF reference did not converge at every level");
  }
  return newton.q();
}

void BM_QsmaCommand(benchmark::State& state) {
  reference();  // builds the model files once, outside the timing
  size_t points = 0;
  for (auto _ : state) {
    const auto curve = qsma_command();
    points = curve.size();
    benchmark::DoNotOptimize(curve.data());
  }
  state.counters["points"] = static_cast<double>(points);
  state.counters["dofs"] = static_cast<double>(reference().model.size());
}
BENCHMARK(BM_QsmaCommand)->Unit(benchmark::kMillisecond);

void BM_QsmaAllDofNewton(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(all_dof_curve());
  state.counters["points"] = static_cast<double>(reference().alphas.size());
}
BENCHMARK(BM_QsmaAllDofNewton)->Unit(benchmark::kMillisecond)->Iterations(3);

void BM_QsmaSpeedup(benchmark::State& state) {
  using Clock = std::chrono::steady_clock;
  reference();  // builds the model files once, outside the timing
  double command = 0, all_dofs = 0;
  for (auto _ : state) {
    const auto t0 = Clock::now();
    benchmark::DoNotOptimize(qsma_command().data());
    const auto t1 = Clock::now();
    benchmark::DoNotOptimize(all_dof_curve());
    const auto t2 = Clock::now();
    command += std::chrono::duration<double>(t1 - t0).count();
    all_dofs += std::chrono::duration<double>(t2 - t1).count();
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["command_ms"] = 1e3 * command / n;
  state.counters["all_dof_ms"] = 1e3 * all_dofs / n;
  state.counters["speedup"] = all_dofs / command;
}
BENCHMARK(BM_QsmaSpeedup)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

int main(int argc, char** argv) { return jointlab::bench::run_benchmarks(argc, argv, work_dir()); }
