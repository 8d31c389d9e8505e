#include "jointlab/model/model_file_writer.h"

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "jointlab/core/error.h"
#include "jointlab/data/matrix_market.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::model {
namespace {

namespace fs = std::filesystem;

fs::path fresh(const std::string& name) {
  const fs::path d = jointlab::testing::scratch_folder("jointlab_model_file_writer_test_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// Three DOFs, an Iwan element between 0 and 1, a spring from 2 to ground.
Model three_dofs(bool labels) {
  Model m;
  m.mass.resize(3, 3);
  m.stiffness.resize(3, 3);
  for (int i = 0; i < 3; ++i) m.mass.insert(i, i) = 1.0 + i / 3.0;
  m.stiffness.insert(0, 0) = 100;
  m.stiffness.insert(1, 1) = 200;
  m.stiffness.insert(2, 2) = 100;
  m.stiffness.insert(1, 2) = m.stiffness.insert(2, 1) = -100;
  Joint a;
  a.a = 0;
  a.b = 1;
  a.element = "iwan.rivet";
  a.iwan = Iwan(40.0, 2.0e6, -0.4321, 0.7);
  a.stiffness = 2.0e6;
  Joint b;
  b.a = 2;
  b.b = kGround;
  b.element = "spring.kz";
  b.stiffness = 1.0 / 3.0 * 1e7;
  m.joints = {a, b, a};
  if (labels) m.dof_labels = {"1001:1", "1001:2", "1002:1"};
  validate_model(m, "test");
  return m;
}

void expect_same(const Model& r, const Model& m) {
  EXPECT_EQ((Eigen::MatrixXd(r.mass) - Eigen::MatrixXd(m.mass)).norm(), 0.0);
  EXPECT_EQ((Eigen::MatrixXd(r.stiffness) - Eigen::MatrixXd(m.stiffness)).norm(), 0.0);
  ASSERT_EQ(r.joints.size(), m.joints.size());
  for (size_t i = 0; i < m.joints.size(); ++i) {
    EXPECT_EQ(r.joints[i].a, m.joints[i].a);
    EXPECT_EQ(r.joints[i].b, m.joints[i].b);
    EXPECT_EQ(r.joints[i].element, m.joints[i].element);
    EXPECT_EQ(r.joints[i].stiffness, m.joints[i].stiffness);  // exact round trip
    ASSERT_EQ(r.joints[i].iwan.has_value(), m.joints[i].iwan.has_value());
    if (m.joints[i].iwan) {
      EXPECT_EQ(r.joints[i].iwan->slip_force(), m.joints[i].iwan->slip_force());
      EXPECT_EQ(r.joints[i].iwan->chi(), m.joints[i].iwan->chi());
      EXPECT_EQ(r.joints[i].iwan->beta(), m.joints[i].iwan->beta());
    }
  }
  EXPECT_EQ(r.dof_labels, m.dof_labels);
  EXPECT_EQ(r.modal_ratio, m.modal_ratio);  // exact round trip
}

TEST(ModelFileWriter, RoundTripsWithMatricesWrittenBeside) {
  for (bool labels : {false, true}) {
    const fs::path d = fresh(labels ? "labels" : "plain");
    const Model m = three_dofs(labels);
    write_model_file(d / "model.toml", m);
    EXPECT_TRUE(fs::exists(d / "mass.mtx"));
    EXPECT_EQ(fs::exists(d / "dof_labels.csv"), labels);
    expect_same(read_model(d / "model.toml"), m);
  }
}

// The structure's own damping ([damping] modal_ratio) is written back exactly; a model without
// it gets no [damping] table (and reads back 0).
TEST(ModelFileWriter, RoundTripsTheModalDampingRatio) {
  const fs::path d = fresh("damping");
  Model m = three_dofs(false);
  m.modal_ratio = 6.7e-4 / 3;
  write_model_file(d / "model.toml", m);
  EXPECT_NE(jointlab::testing::read_file(d / "model.toml").find("[damping]\nmodal_ratio = "),
            std::string::npos);
  expect_same(read_model(d / "model.toml"), m);
  m.modal_ratio = 0;
  write_model_file(d / "model.toml", m);
  EXPECT_EQ(jointlab::testing::read_file(d / "model.toml").find("[damping]"), std::string::npos);
  expect_same(read_model(d / "model.toml"), m);
}

TEST(ModelFileWriter, ReferencesExistingMatricesByRelativePath) {
  const fs::path d = fresh("reference");
  fs::create_directories(d / "fe" / "matrices");
  fs::create_directories(d / "updated");
  const Model m = three_dofs(false);
  data::write_matrix_market(d / "fe" / "matrices" / "M.mtx", m.mass, true);
  data::write_matrix_market(d / "fe" / "matrices" / "K.mtx", m.stiffness, false);
  write_model_file(d / "updated" / "model.toml", m,
                   {d / "fe" / "matrices" / "M.mtx", d / "fe" / "matrices" / "K.mtx", {}});
  EXPECT_FALSE(fs::exists(d / "updated" / "mass.mtx"));
  const std::string text = model_file_text(m, "a.mtx", "b.mtx", "");
  EXPECT_NE(text.find("Kt = 2000000.0"), std::string::npos) << text;
  std::ifstream in(d / "updated" / "model.toml");
  const std::string written((std::istreambuf_iterator<char>(in)), {});
  EXPECT_NE(written.find("mass = \"../fe/matrices/M.mtx\""), std::string::npos) << written;
  expect_same(read_model(d / "updated" / "model.toml"), m);
}

TEST(ModelFileWriter, RefusesElementNamesTheFormatCannotHold) {
  Model m = three_dofs(false);
  m.joints[1].element = "kz";
  EXPECT_NE(
      testing::input_error_of([&] { model_file_text(m, "a", "b", ""); }).find("spring.<name>"),
      std::string::npos);
}

}  // namespace
}  // namespace jointlab::model
