// End to end on a known truth (method.md section 3): the single-mass Iwan oscillator is
// struck, its ring-down written as a contract CSV record and read back, and the test-side
// pipeline (modal::process_record) must return the closed-form QSMA backbone.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "jointlab/data/csv_reader.h"
#include "jointlab/data/record_writer.h"
#include "jointlab/modal/process.h"
#include "jointlab/model/sim/ringdown_simulation.h"
#include "jointlab/model/sim/simulated_record.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::model {
namespace {

// m = 1 kg, k0 and an Iwan element to ground: 400 Hz linear, zeta from 0.22 % at the
// largest amplitude the 80 N pulse reaches down to 0.015 % two decades lower.
const IwanParameters kIwan{400.0, 1.6e6, -0.5, 0.1};
constexpr double kK0 = 4.717e6;

Model oscillator() {
  Model m;
  m.mass.resize(1, 1);
  m.mass.insert(0, 0) = 1.0;
  m.stiffness.resize(1, 1);
  m.stiffness.insert(0, 0) = kK0;
  m.joints.push_back(Joint{0, kGround, "iwan.j", kIwan.Kt, Iwan(kIwan)});
  return m;
}

modal::Backbone backbone(int substeps, double* closure) {
  const Model m = oscillator();
  SimulationOptions o;
  o.pulse = {0, 80.0, 5e-4, 0.01};
  o.sensors = {0};
  o.fs = 8000;
  o.duration = 5;
  o.substeps = substeps;
  SimulationSummary s;
  const SimulatedResponse r = simulate_ringdown(m, o, &s);
  EXPECT_EQ(s.status, SimulationStatus::kOk);
  *closure = s.energy.relative_closure();
  RecordOptions ro;
  ro.model_name = "oscillator";
  const std::string csv = data::format_csv_record(make_simulated_record(m, o, r, s, ro));
  const data::Record rec = data::parse_csv(csv, "oscillator.csv");
  modal::ProcessOptions po;
  po.bands = {{300, 500}};
  po.ringdown.amplitude = Quantity::kDisplacement;
  signal::FftCache cache;
  const modal::RecordResult res = modal::process_record(rec, po, cache);
  EXPECT_EQ(res.results.size(), 1u);
  return res.results.at(0).ringdown.backbone;
}

TEST(SimulateProcess, OscillatorBackboneMatchesClosedFormQsma) {
  // QSMA assumes the energy at a turning point is the backbone's k0 A^2/2 + int F; with
  // Masing sliders it is lower by what they dissipated on the way up, so the ring-down's
  // zeta exceeds QSMA's by about 4 zeta (0.9 % at zeta = 0.22 %, ringdown_simulation_test
  // checks the corrected form). The frequency differs from QSMA's secant by 1.9 % of the
  // softening's shift (first harmonic of the Masing loop against its secant): 2e-4 here.
  // Bounds: 5e-4 in frequency, 1 % in damping, over at least 1.5 decades.
  double closure = 0;
  const modal::Backbone b = backbone(0, &closure);
  ASSERT_GT(b.size(), 50);
  const Iwan iwan(kIwan);
  const double decades = std::log10(b.amplitude.maxCoeff() / b.amplitude.minCoeff());
  EXPECT_GE(decades, 1.5);
  double worst_f = 0, worst_z = 0;
  for (Eigen::Index i = 0; i < b.size(); ++i) {
    const double a = b.amplitude(i), ks = kK0 * a + iwan.force(a);
    const double f = std::sqrt(ks / a) / (2 * M_PI);
    const double zeta = iwan.dissipation(a) / (2 * M_PI * ks * a);
    worst_f = std::max(worst_f, testing::rel_err(b.frequency_hz(i), f));
    worst_z = std::max(worst_z, testing::rel_err(b.damping(i), zeta));
  }
  EXPECT_LT(worst_f, 5e-4);
  EXPECT_LT(worst_z, 1e-2);
  RecordProperty("decades", std::to_string(decades));
  RecordProperty("worst_frequency_rel", std::to_string(worst_f));
  RecordProperty("worst_damping_rel", std::to_string(worst_z));
  EXPECT_LT(closure, 1e-3);
}

TEST(SimulateProcess, HalvingTheStepLeavesTheDampingUnchanged) {
  // Newmark's period error (omega dt)^2/12 is 1e-5 at the automatic 29 substeps; halving the
  // step must move the extracted damping by less than 0.2 % at every common amplitude, and
  // the energy balance must close within 0.1 % of the input (both fall as dt^2).
  double c1 = 0, c2 = 0;
  const modal::Backbone b1 = backbone(29, &c1), b2 = backbone(58, &c2);
  EXPECT_LT(c1, 1e-3);
  EXPECT_LT(c2, c1 / 3);
  // Backbones run in time, amplitude decreasing: interpolate b2 in log amplitude.
  std::vector<double> la, z;
  for (Eigen::Index i = b2.size(); i-- > 0;) {
    la.push_back(std::log(b2.amplitude(i)));
    z.push_back(b2.damping(i));
  }
  int compared = 0;
  for (Eigen::Index i = 0; i < b1.size(); ++i) {
    const double x = std::log(b1.amplitude(i));
    if (x < la.front() || x > la.back()) continue;
    size_t k = 1;
    while (la[k] < x) ++k;
    const double w = (x - la[k - 1]) / (la[k] - la[k - 1]);
    const double z2 = z[k - 1] + w * (z[k] - z[k - 1]);
    EXPECT_LT(testing::rel_err(b1.damping(i), z2), 2e-3) << "amplitude " << b1.amplitude(i);
    ++compared;
  }
  EXPECT_GT(compared, 50);
}

}  // namespace
}  // namespace jointlab::model
