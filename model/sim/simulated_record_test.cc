#include "jointlab/model/sim/simulated_record.h"

#include <cmath>

#include <gtest/gtest.h>

#include "jointlab/core/error.h"
#include "jointlab/data/csv_reader.h"
#include "jointlab/data/record_writer.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::model {
namespace {

using testing::Close;

// Two masses on springs to ground, coupled by an Iwan element; labelled DOFs.
Model pair(bool labels) {
  Model m;
  m.mass.resize(2, 2);
  m.mass.insert(0, 0) = 1.0;
  m.mass.insert(1, 1) = 2.0;
  m.stiffness.resize(2, 2);
  m.stiffness.insert(0, 0) = 4e6;
  m.stiffness.insert(1, 1) = 6e6;
  const IwanParameters p{200.0, 1e6, -0.5, 0.5};
  m.joints.push_back(Joint{0, 1, "iwan.j", p.Kt, Iwan(p)});
  if (labels) m.dof_labels = {"9001:3", "9002:1"};
  return m;
}

TEST(SimulatedRecord, ResolvesIndicesAndLabels) {
  const Model m = pair(true);
  EXPECT_EQ(resolve_dof(m, "1", "--impact"), 1);
  EXPECT_EQ(resolve_dof(m, "9001:3", "--impact"), 0);
  EXPECT_THROW(resolve_dof(m, "2", "--impact"), InputError);
  EXPECT_THROW(resolve_dof(m, "9001:4", "--impact"), InputError);
  EXPECT_THROW(resolve_dof(m, "-1", "--impact"), InputError);
  EXPECT_THROW(resolve_dof(m, "", "--impact"), InputError);
  EXPECT_THROW(resolve_dof(pair(false), "9001:3", "--sensors"), InputError);
  // A label the model lacks: the message names the labels its node has (the fix), or says the
  // node is absent. Before: only "is not a label of the model's dof_labels".
  EXPECT_EQ(testing::input_error_of([&] { resolve_dof(m, "9001:1", "--dof"); }),
            "--dof = \"9001:1\" is not a label of the model's dof_labels: node 9001 has only "
            "9001:3");
  EXPECT_NE(testing::input_error_of([&] {
              resolve_dof(m, "9005:1", "--dof");
            }).find("is not a label of the model's dof_labels: it has no node 9005"),
            std::string::npos);
  try {
    resolve_dof(m, "abc", "--sensors");
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--sensors"), std::string::npos);
  }
  EXPECT_EQ(sensor_channel_name(m, 0), "acc_9001_z");
  EXPECT_EQ(sensor_channel_name(m, 1), "acc_9002_x");
  EXPECT_EQ(sensor_channel_name(pair(false), 1), "acc_1");
  EXPECT_EQ(dof_name(m, 0), "9001:3");
}

SimulationOptions options() {
  SimulationOptions o;
  o.pulse = {0, 50.0, 5e-4, 0.01};
  o.sensors = {0, 1};
  o.fs = 5000;
  o.duration = 0.4;
  o.substeps = 8;
  return o;
}

// The pair's simulated ring-down under options(), what make_simulated_record() turns into a
// record.
struct Ringdown {
  Model m;
  SimulationOptions o = options();
  SimulationSummary s;
  SimulatedResponse r;
  explicit Ringdown(bool labels) : m(pair(labels)), r(simulate_ringdown(m, o, &s)) {}
};

TEST(SimulatedRecord, WritesTheContractsCsvWithMetadata) {
  const Ringdown d(true);
  const auto& [m, o, s, r] = d;
  RecordOptions ro;
  ro.model_name = "pair.toml";
  const data::Record rec = make_simulated_record(m, o, r, s, ro);
  const std::string text = data::format_csv_record(rec);
  EXPECT_NE(text.find("# fs: 5000\n"), std::string::npos);
  EXPECT_NE(text.find("# model: pair.toml\n"), std::string::npos);
  EXPECT_NE(text.find("# impact_dof: 9001:3\n"), std::string::npos);
  EXPECT_NE(text.find("# force_N: 50\n"), std::string::npos);
  EXPECT_NE(text.find("acc_9001_z [m/s^2],acc_9002_x [m/s^2]\n"), std::string::npos);
  const data::Record back = data::parse_csv(text, "sim.csv");
  ASSERT_EQ(back.channels.size(), 2u);
  EXPECT_EQ(back.fs, 5000);
  EXPECT_EQ(back.channels[1].samples, r.acceleration.col(1));  // shortest round-trip digits
}

TEST(SimulatedRecord, NoiseHasTheRequestedLevelAndSeed) {
  // White Gaussian noise of standard deviation 1 % of each channel's peak: over 2000
  // samples the sample standard deviation is within 3 / sqrt(2 * 2000) = 5 % of it.
  const Ringdown d(false);
  const auto& [m, o, s, r] = d;
  RecordOptions ro;
  ro.noise = 0.01;
  ro.seed = 42;
  const data::Record a = make_simulated_record(m, o, r, s, ro);
  const data::Record b = make_simulated_record(m, o, r, s, ro);
  ro.seed = 43;
  const data::Record c = make_simulated_record(m, o, r, s, ro);
  EXPECT_EQ(a.channels[0].samples, b.channels[0].samples);
  EXPECT_NE(a.channels[0].samples, c.channels[0].samples);
  for (Eigen::Index k = 0; k < 2; ++k) {
    const Eigen::VectorXd clean = r.acceleration.col(k);
    const Eigen::VectorXd noise = a.channels[static_cast<size_t>(k)].samples - clean;
    const double sd = std::sqrt(noise.squaredNorm() / static_cast<double>(noise.size()));
    EXPECT_TRUE(Close(sd, 0.01 * clean.cwiseAbs().maxCoeff(), 0.05));
  }
  ro.noise = -1;
  EXPECT_THROW(make_simulated_record(m, o, r, s, ro), InputError);
}

}  // namespace
}  // namespace jointlab::model
