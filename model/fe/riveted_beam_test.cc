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

// [[joint_set]]: a bolt pair at the ends beside riveted ones is two Iwan sets, which a
// description could not say (a two-set beam's model.toml had its 8 bolt elements renamed by
// hand). The named rivets' x and y elements become iwan.<name>, their parameters default to
// [joints]'; a rivet in two sets, a rivet that does not exist, the name "rivet" and an Iwan
// parameter out of its domain are refused naming the field.
TEST(RivetedBeam, AJointSetGivesItsRivetsAnIwanSetOfTheirOwn) {
  const std::string head =
      "[mesh]\nelement = \"beam\"\nsize = 0.01\n[rivets]\npositions = [[0.02, 0.0], "
      "[0.24, 0.0], [0.26, 0.0], [0.48, 0.0]]\n[joints]\nFs = 40.0\nchi = -0.5\n";
  const RivetedBeamDescription d = read_riveted_beam_description(
      scratch("sets.toml",
              head + "[[joint_set]]\nname = \"bolt\"\nrivets = [1, 4]\nKt = 2e7\nFs = 60.0\n"));
  ASSERT_EQ(d.joint_sets.size(), 1u);
  const IwanParameters bolt = joint_iwan(d, "iwan.bolt"), rivet = joint_iwan(d, "iwan.rivet");
  EXPECT_EQ(bolt.Kt, 2e7);
  EXPECT_EQ(bolt.Fs, 60.0);
  EXPECT_EQ(bolt.chi, -0.5);  // [joints]'
  // chi above 0 is in the domain (method.md: -1 < chi): a set of its own takes it.
  const RivetedBeamDescription above = read_riveted_beam_description(
      scratch("above.toml", head + "[[joint_set]]\nname = \"bolt\"\nrivets = [1, 4]\nchi = 0.5\n"));
  EXPECT_EQ(joint_iwan(above, "iwan.bolt").chi, 0.5);
  EXPECT_EQ(rivet.Fs, 40.0);
  EXPECT_EQ(joint_stiffness(d, "iwan.bolt"), 2e7);
  const RivetedBeam b = build_riveted_beam(d);
  ASSERT_EQ(b.joints.size(), 4u * 6u);
  for (const RivetJoint& j : b.joints) {
    const bool bolted = j.rivet == 1 || j.rivet == 4;
    if (j.component <= 2) {
      EXPECT_EQ(j.element, bolted ? "iwan.bolt" : "iwan.rivet") << j.rivet;
    } else if (j.component == 3) {
      EXPECT_EQ(j.element, "spring.kz");
    }
  }
  const auto says = [&](const std::string& sets, const std::string& what) {
    const std::string e = error_of(head + sets);
    EXPECT_NE(e.find(what), std::string::npos) << e;
  };
  says("[[joint_set]]\nname = \"bolt\"\nrivets = [5]\n",
       "field 'joint_set[1].rivets': rivet 5 does not exist (1 to 4)");
  says("[[joint_set]]\nname = \"a\"\nrivets = [1]\n[[joint_set]]\nname = \"b\"\nrivets = [1]\n",
       "field 'joint_set[2].rivets': rivet 1 is in set 'a' already");
  says("[[joint_set]]\nname = \"rivet\"\nrivets = [1]\n", "'joint_set[1].name' = 'rivet' is taken");
  says("[[joint_set]]\nname = \"bolt\"\nrivets = [1]\nchi = -1.0\n",
       "field 'joint_set[1].chi' = -1 must be > -1");
  says("[[joint_set]]\nname = \"bolt\"\nrivets = [1]\nKs = 1.0\n", "joint_set[1].Ks");
  says("[[joint_set]]\nrivets = [1]\n", "'joint_set[1].name' is required");
}

}  // namespace
}  // namespace jointlab::model::fe
