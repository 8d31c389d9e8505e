// Measured modes as other labs' tools export them, read by update-linear: angular frequencies
// under frequency_hz, columns of damping, MPC and MPD beside the shapes, and a sensor given as
// mounted along -z. Each is either read as meant or refused naming what to write instead.
#include <complex>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "jointlab/core/error.h"
#include "jointlab/correlate/linear_update.h"
#include "jointlab/correlate/measured_data.h"
#include "jointlab/correlate/sensors.h"
#include "jointlab/correlate/two_chain.h"
#include "jointlab/model/linear_modes.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::correlate {
namespace {

namespace fs = std::filesystem;

// The two chains' lowest `count` modes at four sensors per chain, noise-free, frequencies in Hz.
MeasuredModes chain_modes(const model::Model& truth, const std::vector<Sensor>& sensors,
                          int count) {
  const model::LinearModes modes = model::linear_modes(truth.mass, truth.linear_stiffness());
  const Eigen::MatrixXd at = shapes_at_sensors(sensors, modes.shapes);
  MeasuredModes m;
  m.frequency_hz.resize(count);
  for (int i = 0; i < count; ++i) m.frequency_hz(i) = modes.frequency_hz(modes.rigid_count + i);
  m.shapes = at.middleCols(modes.rigid_count, count).cast<std::complex<double>>();
  return m;
}

std::vector<Sensor> chain_sensors(int n) {
  std::vector<Sensor> s;
  for (int c = 0; c < 2; ++c)
    for (int i : {0, 2, 3, 5}) s.push_back({fmt::format("s{}", c * n + i), c * n + i, 1.0});
  return s;
}

// Angular frequencies (rad/s) written under frequency_hz: read as Hz, each is 2 pi times its
// mode's. On the example beam (five z sensors, six bending modes, truth K_T 3e7, start 1e7)
// the fit paired them with model modes 7 to 39 (five sensors alias bending modes), left a
// reduced chi-square of 4.3e4 and ended "pairs unconfirmed" with K_T 7.8e6 +/- 93 %; with three
// sensors "converged" with K_T 1.5e5, never naming the unit. Here: the twenty-mass chains (its
// modes reach 2 pi times the lowest ones) with ka started at twice the truth; now refused, the
// fit divided by 2 pi naming the fix. The same modes in Hz are not (the check runs only where a
// fit leaves scatter beyond the noise).
TEST(ModesTableFromAnotherTool, AngularFrequenciesReadAsHzAreNamed) {
  TwoChainParameters truth;
  truth.n = 20;
  const model::Model m = two_chain_structure(truth);
  const std::vector<Sensor> sensors = chain_sensors(truth.n);
  MeasuredModes hz = chain_modes(m, sensors, 6);
  TwoChainParameters begin = truth;
  begin.ka *= 2;
  const model::Model start = two_chain_structure(begin);
  const std::vector<std::string> sets = {"spring.ka", "spring.kb"};
  MeasuredModes rad = hz;
  rad.frequency_hz *= 2 * std::numbers::pi;
  LinearUpdateSummary s;
  update_linear(start, sets, sensors, rad, {}, &s);
  ASSERT_EQ(s.status, LinearUpdateStatus::kShapesRefused) << s.report();
  const std::string why = linear_refusal(s, {}, "modes.csv");
  EXPECT_EQ(why.find("modes.csv: the frequencies look like angular frequencies (rad/s) read as Hz"),
            0u)
      << why;
  EXPECT_NE(why.find("give frequency_hz in Hz (rad/s divided by 2 pi)"), std::string::npos) << why;
  // Noise-free modes in Hz from a start the fit can leave: converged (the rad/s refit is not
  // tried where the fit is within the noise).
  LinearUpdateSummary given;
  update_linear(start, sets, sensors, hz, {}, &given);
  EXPECT_EQ(given.status, LinearUpdateStatus::kConverged) << given.report();
}

// Columns other tools write beside the shapes (damping ratio, MPC, MPD, in any case and with a
// unit) are left out, the shapes read exactly as without them; a column neither a sensor nor
// one of those is refused naming the sensors' channels, and a frequency header in rad/s says
// what to give instead of only what the header must be.
TEST(ModesTableFromAnotherTool, DampingAndMpcColumnsAreLeftOutAndTheRestNamed) {
  const fs::path d = jointlab::testing::scratch_folder("jointlab_foreign_tables_test");
  const std::vector<Sensor> sensors{{"z1", 1, 1.0}, {"z2", 2, 1.0}, {"z3", 3, 1.0}};
  const auto write = [&](const std::string& file, const std::string& text) {
    std::ofstream(d / file) << text;
    return d / file;
  };
  const MeasuredModes plain = read_modes_table(
      write("plain.csv", "mode,frequency_hz,z1,z2,z3\n1,57.9,0.5,-0.25,1\n2,120,1,0.5,-0.75\n"),
      sensors, nullptr);
  const MeasuredModes extra = read_modes_table(
      write("extra.csv",
            "mode,frequency_hz,Damping [%],z1,z2,z3,damping_ratio,MPC,mpd (deg)\n"
            "1,57.9,0.12,0.5,-0.25,1,0.0012,0.998,1.5\n2,120,0.2,1,0.5,-0.75,0.002,0.97,4\n"),
      sensors, nullptr);
  // Exact: the same cells parse to the same doubles, so any difference is a column misread.
  ASSERT_EQ(extra.frequency_hz.size(), 2);
  EXPECT_EQ(extra.frequency_hz, plain.frequency_hz);
  EXPECT_EQ(extra.shapes, plain.shapes);
  const std::string unknown = jointlab::testing::input_error_of([&] {
    read_modes_table(write("unknown.csv", "mode,frequency_hz,z1,acc4\n1,57.9,1,2\n"), sensors,
                     nullptr);
  });
  EXPECT_NE(unknown.find("unknown.csv:1: column 'acc4' is not a sensor channel (the sensors file "
                         "has 3 channels: z1, z2, z3)"),
            std::string::npos)
      << unknown;
  const std::string rad = jointlab::testing::input_error_of([&] {
    read_modes_table(write("rad.csv", "mode,frequency_rad_s,z1\n1,363.8,1\n"), sensors, nullptr);
  });
  EXPECT_NE(rad.find("rad.csv:1: column 'frequency_rad_s': frequencies are read in Hz only, "
                     "under frequency_hz: give them so (rad/s divided by 2 pi)"),
            std::string::npos)
      << rad;
}

// A sensor mounted upside down written as a direction (9001:-z, as test-modal tools label
// their channels) names the label and sign to give instead.
TEST(ModesTableFromAnotherTool, ASensorAlongMinusZNamesTheLabelAndSign) {
  model::Model m = two_chain_structure();
  m.dof_labels.clear();
  for (int i = 0; i < m.size(); ++i) m.dof_labels.push_back(std::to_string(9000 + i) + ":3");
  const auto error = [&](const std::string& text) {
    return jointlab::testing::input_error_of([&] { parse_sensors(text, "s.csv", m); });
  };
  EXPECT_NE(error("channel,dof\na,9001:-z\n")
                .find("s.csv:2: dof '9001:-z' is not a label of the model's dof_labels: node "
                      "9001 has only 9001:3 (a component is a number, 1-6 for x, y, z, rx, ry, "
                      "rz, and a channel that reads against it has sign -1: give 9001:3 and sign "
                      "-1)"),
            std::string::npos)
      << error("channel,dof\na,9001:-z\n");
  EXPECT_NE(error("channel,dof\na,9001:Z\n").find("give 9001:3)"), std::string::npos)
      << error("channel,dof\na,9001:Z\n");
  // A component the node lacks, written as a number, gets no direction hint; as a direction,
  // the rule without a label the model lacks.
  EXPECT_EQ(error("channel,dof\na,9001:1\n").find("a component is a number"), std::string::npos);
  EXPECT_NE(error("channel,dof\na,9001:-x\n").find("reads against it has sign -1)"),
            std::string::npos)
      << error("channel,dof\na,9001:-x\n");
}

}  // namespace
}  // namespace jointlab::correlate

namespace jointlab::correlate {
namespace {

// Modes that no set moves (y sensors on a stacked beam's in-plane modes; here the stiff
// spring.kflat at 1e10, sensitivity far below 1e-3, alone): the flat set is held where the fit
// left it. Before, the headline said only "converged" and the warning "(it had drifted to
// 1e+07)" of a set held at 1e+07; now the headline says no set was fitted and the warning that
// the fit left it there.
TEST(ModesTableFromAnotherTool, ModesNoSetMovesSayNoSetWasFitted) {
  const model::Model m = two_chain_structure();
  const std::vector<Sensor> sensors = chain_sensors(6);
  LinearUpdateSummary s;
  update_linear(m, {"spring.kflat"}, sensors, chain_modes(m, sensors, 4), {}, &s);
  const std::string report = s.report();
  ASSERT_EQ(s.status, LinearUpdateStatus::kConverged) << report;
  ASSERT_TRUE(s.parameters.at(0).held) << report;
  EXPECT_NE(report.find("%; no set fitted: each is held (below), so these modes identify none "
                        "of them\n"),
            std::string::npos)
      << report;
  EXPECT_NE(report.find("held at 1e+10 (the fit left it there)"), std::string::npos) << report;
}

}  // namespace
}  // namespace jointlab::correlate
