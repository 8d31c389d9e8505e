#include "jointlab/model/fe/riveted_beam.h"

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "jointlab/core/error.h"
#include "jointlab/model/fe/model_builder.h"
#include "jointlab/model/sparse_eigen.h"
#include "jointlab/tests/free_modes.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::model::fe {
namespace {

namespace fs = std::filesystem;

fs::path scratch(const std::string& name, const std::string& text) {
  return testing::scratch_file("jointlab-riveted-beam-test", name, text);
}

std::string error_of(const std::string& text) {
  try {
    read_riveted_beam_description(scratch("bad.toml", text));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(RivetedBeam, TheExampleDescriptionReadsAndHasTwentyFourStaggeredRivets) {
  const RivetedBeamDescription d = read_riveted_beam_description(
      fs::path(jointlab::testing::source_dir()) / "examples/riveted_beam/description.toml");
  ASSERT_EQ(d.rivets.size(), 24u);
  EXPECT_TRUE(d.shell);
  for (std::size_t i = 0; i < d.rivets.size(); ++i) {
    EXPECT_GT(d.rivets[i].x(), d.length - d.overlap);
    EXPECT_LT(d.rivets[i].x(), d.length);
    if (i > 0) {
      EXPECT_GT(d.rivets[i].x(), d.rivets[i - 1].x());             // along the length
      EXPECT_EQ(d.rivets[i].y() > 0, !(d.rivets[i - 1].y() > 0));  // alternating rows
    }
  }
}

TEST(RivetedBeam, BadDescriptionsNameTheField) {
  EXPECT_NE(error_of("[strips]\nlenght = 0.5\n").find("strips.lenght"), std::string::npos);
  EXPECT_NE(error_of("[strips]\nlength = -1.0\n").find("strips.length"), std::string::npos);
  EXPECT_NE(error_of("[mesh]\nelement = \"brick\"\n").find("mesh.element"), std::string::npos);
  EXPECT_NE(error_of("[strips]\nwidth = \"wide\"\n").find("strips.width"), std::string::npos);
  EXPECT_NE(error_of("[rivets]\npositions = [[0.7, 0.0]]\n").find("rivet 1"), std::string::npos);
  EXPECT_NE(error_of("[[sensor]]\nx = 0.1\ncomponents = [\"w\"]\n").find("sensor[1]"),
            std::string::npos);
  EXPECT_NE(error_of("[strips\n").find("bad.toml:"), std::string::npos);
  EXPECT_EQ(error_of("[strips]\nlength = 0.4\n"), "");  // a valid partial file
}

// Number of rigid-body modes (f < 0.1 Hz; round-off leaves them near 1e-3 Hz, the first
// elastic mode of these beams is above 10 Hz) of the model with every joint scaled by s
// (s = 0: unjoined).
int rigid_modes(const RivetedBeamDescription& d, double s) {
  const RivetedBeam b = build_riveted_beam(d);
  const AssembledModel a = b.fe.assemble();
  RivetedBeamDescription stiff = d;
  stiff.kt *= s;
  stiff.kz *= s;
  stiff.rxy *= s;
  stiff.rz *= s;
  const Eigen::SparseMatrix<double> k =
      s == 0 ? a.stiffness : with_joints(a.stiffness, b.joints, stiff, [&](int node, int c) {
        return a.dof(node, c - 1);
      });
  const EigenResult r = jointlab::testing::free_modes(k, a.mass, 16);
  const Eigen::VectorXd f = frequencies_hz(r.eigenvalues);
  int n = 0;
  while (n < f.size() && f(n) < 0.1) ++n;
  EXPECT_GT(f(n), 10.0) << "no clear gap after " << n << " modes";
  return n;
}

RivetedBeamDescription coarse(bool shell) {
  RivetedBeamDescription d = default_riveted_beam();
  d.shell = shell;
  d.element_size = 0.005;
  d.coupling_radius = 0.007;  // ≥ 3 nodes of the 5 mm × 4.2 mm grid per patch
  return d;
}

TEST(RivetedBeam, ShellCouplingsPassRigidBodyMotion) {
  // Unjoined: each strip with its 24 coupled reference nodes moves freely (12 modes).
  // Stiff rivets (1000 × the default springs): the assembly moves as one body (6 modes).
  EXPECT_EQ(rigid_modes(coarse(true), 0), 12);
  EXPECT_EQ(rigid_modes(coarse(true), 1e3), 6);
}

TEST(RivetedBeam, BeamLinksPassRigidBodyMotion) {
  EXPECT_EQ(rigid_modes(coarse(false), 0), 12);
  EXPECT_EQ(rigid_modes(coarse(false), 1e3), 6);
}

TEST(RivetedBeam, TooSmallCouplingRadiusIsReported) {
  RivetedBeamDescription d = coarse(true);
  d.coupling_radius = 0.001;  // no 3 shell nodes within 1 mm on a 5 mm mesh
  EXPECT_THROW(build_riveted_beam(d), InputError);
}

}  // namespace
}  // namespace jointlab::model::fe
