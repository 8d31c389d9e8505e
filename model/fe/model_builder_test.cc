#include "jointlab/model/fe/model_builder.h"

#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "jointlab/model/model_file.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::model::fe {
namespace {

namespace fs = std::filesystem;
using jointlab::testing::rel_err;

// A coarse shell riveted beam (5 mm elements, ~8 000 DOFs) so the test stays fast.
RivetedBeamDescription coarse() {
  RivetedBeamDescription d = default_riveted_beam();
  d.element_size = 0.005;
  d.coupling_radius = 0.007;  // ≥ 3 nodes of the 5 mm × 4.2 mm grid per patch
  return d;
}

// The first `n` elastic eigenvalues (after the six rigid-body modes) of the reduced model, by a
// dense solve of its own.
Eigen::VectorXd reduced_elastic(const ReducedModel& m, int n) {
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(
      Eigen::MatrixXd(with_joints(m)), Eigen::MatrixXd(m.mass));
  return es.eigenvalues().segment(6, n);
}

TEST(ModelBuilder, ReducedFrequenciesMatchTheFullModelAndImproveWithModes) {
  RivetedBeamDescription d = coarse();
  // The full model's first 10 elastic frequencies [Hz] (shift-invert Lanczos on the sparse
  // matrices; an InputError when it does not converge).
  Eigen::VectorXd full;
  ASSERT_NO_THROW(full = full_elastic_frequencies_hz(d, 10));
  double previous = INFINITY;
  for (int m : {0, 10, 30, 60}) {
    d.fixed_interface_modes = m;
    const ReducedModel r = build_reduced_model(d, {});
    ASSERT_TRUE(r.summary.ok) << r.summary.report;
    const Eigen::VectorXd red = reduced_elastic(r, 10);
    double worst = 0;  // worst relative frequency error
    for (int k = 0; k < 10; ++k) {
      worst = std::max(worst, std::sqrt(red(k)) / (2 * std::numbers::pi * full(k)) - 1);
    }
    RecordProperty("modes" + std::to_string(m) + "_worst_rel_err", std::to_string(worst));
    EXPECT_GT(worst, -1e-9) << "Ritz values bound the full ones from above";
    EXPECT_LT(worst, previous) << m << " modes";
    previous = worst;
  }
  // Acceptance: with the default 60 fixed-interface modes, within 0.1 %. (The slowest modes
  // to converge are in-plane ones, whose fixed-interface partners are membrane modes.)
  EXPECT_LT(previous, 1e-3);
}

TEST(ModelBuilder, WritesAModelDirectoryThatReadsBack) {
  RivetedBeamDescription d = coarse();
  d.fixed_interface_modes = 8;
  d.source = "coarse.toml";
  const ReducedModel r = build_reduced_model(d, {});
  ASSERT_TRUE(r.summary.ok);
  const fs::path dir = jointlab::testing::scratch_folder("jointlab_model_builder_test");
  fs::remove_all(dir);
  write_model_directory(dir, r);
  const Model m = read_model(dir / "model.toml");
  ASSERT_EQ(m.size(), r.stiffness.rows());
  // 24 rivets × 2 strips × 6 + 5 sensors × 1 boundary DOFs, then 8 modal coordinates.
  EXPECT_EQ(m.size(), 24 * 2 * 6 + 5 + 8);
  ASSERT_EQ(m.joints.size(), 24u * 6u);
  EXPECT_EQ(m.iwan_count(), 48);
  EXPECT_EQ(m.dof_labels.front(), "1001:1");
  EXPECT_EQ(m.dof_labels[24 * 6], "2001:1");
  EXPECT_EQ(m.dof_labels[24 * 12], "9001:3");
  EXPECT_EQ(m.dof_labels.back(), "0:8");
  // The file's linear stiffness is the builder's K with joints, to the 17 digits written.
  const Eigen::MatrixXd diff =
      Eigen::MatrixXd(m.linear_stiffness()) - Eigen::MatrixXd(with_joints(r));
  EXPECT_LT(diff.cwiseAbs().maxCoeff(),
            1e-14 * Eigen::MatrixXd(with_joints(r)).cwiseAbs().maxCoeff());
  EXPECT_LT((Eigen::MatrixXd(m.mass) - Eigen::MatrixXd(r.mass)).cwiseAbs().maxCoeff(),
            1e-14 * Eigen::MatrixXd(r.mass).cwiseAbs().maxCoeff());
}

// A description with a [[joint_set]] writes a model file of two Iwan sets, each with its own
// parameters, that reads back (a beam model of four rivets, the end two bolted).
TEST(ModelBuilder, AJointSetIsWrittenAsAnIwanSetOfItsOwn) {
  RivetedBeamDescription d = default_riveted_beam();
  d.shell = false;
  d.element_size = 0.02;
  d.rivets = {{0.02, 0.0}, {0.24, 0.0}, {0.26, 0.0}, {0.48, 0.0}};
  d.joint_sets.push_back({"bolt", {1, 4}, 2e7, 60.0, -0.4, 1.0});
  d.fixed_interface_modes = 4;
  d.source = "sets.toml";
  const ReducedModel r = build_reduced_model(d, {});
  ASSERT_TRUE(r.summary.ok);
  const fs::path dir = jointlab::testing::scratch_folder("jointlab_model_builder_sets_test");
  fs::remove_all(dir);
  write_model_directory(dir, r);
  const Model m = read_model(dir / "model.toml");
  int bolts = 0, rivets = 0;
  for (const Joint& j : m.joints) {
    if (!j.iwan) continue;
    if (j.element == "iwan.bolt") {
      ++bolts;
      EXPECT_EQ(j.iwan->slip_force(), 60.0);
      EXPECT_EQ(j.iwan->chi(), -0.4);
      EXPECT_EQ(j.stiffness, 2e7);
    } else {
      ++rivets;
      EXPECT_EQ(j.element, "iwan.rivet");
      EXPECT_EQ(j.iwan->slip_force(), d.fs);
    }
  }
  EXPECT_EQ(bolts, 4);
  EXPECT_EQ(rivets, 4);
}

}  // namespace
}  // namespace jointlab::model::fe
