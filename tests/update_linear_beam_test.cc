// `jointlab update-linear` on the example riveted beam as a new user runs it: the model from
// build-model, six bending modes "measured" at the five z sensors of the description (noise-free,
// made at K_T = 4e7 N/m and rz = 50 N m/rad), four sets, start K_T = 1e7, default options.
// Five sensors alias bending modes (model modes 1/7, 2/6, 5/10 look alike there), and near the
// truth a twisting mode veers with bending mode 6: pairing by MAC alone once ended "converged"
// at K_T 3.58e7 (25 sigma off). About 25 s (5 s for the model, 20 s for the update); the
// one-sensor case about 15 s.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "jointlab/correlate/linear_update.h"
#include "jointlab/correlate/sensors.h"
#include "jointlab/model/linear_modes.h"
#include "jointlab/model/model_file.h"
#include "jointlab/tests/cli.h"
#include "jointlab/tests/test_util.h"

namespace jointlab {
namespace {

namespace fs = std::filesystem;

std::vector<std::vector<std::string>> read_rows(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> cells(1);
    for (char c : line) {
      if (c == ',')
        cells.emplace_back();
      else
        cells.back() += c;
    }
    rows.push_back(cells);
  }
  return rows;
}

// The fitted value of each set in an update's parameters.csv.
std::map<std::string, double> fitted_values(const fs::path& file) {
  std::map<std::string, double> value;
  for (const auto& row : read_rows(file))
    if (row.size() > 2 && row[0] != "name") value[row[0]] = std::stod(row[2]);
  return value;
}

// The six lowest modes of the model at `truth` with clear motion at the five sensors (the
// bending modes: squared norm there above a tenth of the largest among the modes under 2 kHz;
// the twisting and in-plane modes between them have a hundredth or nothing), as a modes table.
std::string bending_table(const model::Model& start, const correlate::StiffnessSets& s,
                          const std::vector<correlate::Sensor>& sensors,
                          const Eigen::VectorXd& truth) {
  const correlate::ElasticModes modes = correlate::elastic_modes(start.mass, s.stiffness(truth));
  const Eigen::MatrixXd at = correlate::shapes_at_sensors(sensors, modes.shapes);
  double top = 0;
  for (Eigen::Index j = 0; j < at.cols() && modes.frequency_hz(j) < 2000; ++j)
    top = std::max(top, at.col(j).squaredNorm());
  std::string table = "mode,frequency_hz,z1,z2,z3,z4,z5\n";
  int rows = 0;
  for (Eigen::Index j = 0; j < at.cols() && rows < 6; ++j) {
    if (at.col(j).squaredNorm() < 0.1 * top) continue;
    table += fmt::format("{},{:.15g}", ++rows, modes.frequency_hz(j));
    for (Eigen::Index r = 0; r < at.rows(); ++r) table += fmt::format(",{:.15g}", at(r, j));
    table += "\n";
  }
  EXPECT_EQ(rows, 6);
  return table;
}

// The modes table dir/modes.csv cut to sensor z3 alone, as dir/one.csv, with dir/sensor.csv.
void write_one_sensor(const fs::path& dir) {
  std::string one = "mode,frequency_hz,z3\n";
  for (const auto& row : read_rows(dir / "modes.csv"))
    if (row.size() == 7 && row[0] != "mode") one += row[0] + "," + row[1] + "," + row[4] + "\n";
  std::ofstream(dir / "one.csv") << one;
  std::ofstream(dir / "sensor.csv") << "channel,dof\nz3,9003:3\n";
}

// The example beam's model, built into dir/model, and its five z sensors.
struct Beam {
  model::Model start;
  std::vector<correlate::Sensor> sensors;
};

Beam build_beam(const fs::path& dir) {
  const std::string description =
      (fs::path(testing::source_dir()) / "examples" / "riveted_beam" / "description.toml").string();
  const testing::CommandResult b = testing::run_jointlab(fmt::format(
      "build-model {} --out {} --quiet --skip-check", description, (dir / "model").string()));
  EXPECT_EQ(b.status, 0) << b.err;
  Beam beam{model::read_model(dir / "model" / "model.toml"), {}};
  std::string sensors_csv = "channel,dof\n";
  for (int i = 1; i <= 5; ++i) sensors_csv += fmt::format("z{},900{}:3\n", i, i);
  std::ofstream(dir / "sensors.csv") << sensors_csv;
  beam.sensors = correlate::sensors_of(data::read_sensors_file(dir / "sensors.csv"), beam.start);
  return beam;
}

TEST(UpdateLinearBeam, FiveSensorsDefaultOptionsFindTheTruth) {
  const fs::path dir = testing::scratch_dir("update_linear_beam");
  const Beam beam = build_beam(dir);
  const model::Model& start = beam.start;
  const std::vector<correlate::Sensor>& sensors = beam.sensors;

  // The truth: K_T 4e7, rz 50.
  const std::vector<std::string> sets = {"iwan.rivet", "spring.kz", "spring.rxy", "spring.rz"};
  const correlate::StiffnessSets s(start, sets);
  Eigen::VectorXd truth = s.initial();
  truth(0) = 4e7;
  truth(3) = 50;
  const std::string table = bending_table(start, s, sensors, truth);
  std::ofstream(dir / "modes.csv") << table;

  const testing::CommandResult r = testing::run_jointlab(fmt::format(
      "update-linear {} --modes-table {} --sensors {} --set iwan.rivet --set spring.kz --set "
      "spring.rxy --set spring.rz --out {}",
      (dir / "model" / "model.toml").string(), (dir / "modes.csv").string(),
      (dir / "sensors.csv").string(), (dir / "out").string()));
  ASSERT_EQ(r.status, 0) << r.out << r.err;
  SCOPED_TRACE(r.out);
  // Progress on stderr, the warnings once in the report.
  EXPECT_NE(r.err.find("update-linear: iteration 1, cost"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("WARNING"), std::string::npos);

  // K_T within 1 % (the acceptance bound; noise-free data, so in fact to the optimiser's
  // tolerance), every mode within 0.1 %, six distinct model modes.
  const std::map<std::string, double> value = fitted_values(dir / "out" / "parameters.csv");
  EXPECT_TRUE(testing::Close(value.at("iwan.rivet"), 4e7, 0.01));
  std::set<std::string> model_modes;
  const auto rows = read_rows(dir / "out" / "modes.csv");
  ASSERT_EQ(rows.size(), 7u);
  for (size_t i = 1; i < rows.size(); ++i) {
    ASSERT_EQ(rows[i].size(), 6u);
    ASSERT_FALSE(rows[i][2].empty()) << "test mode " << i << " unpaired";
    model_modes.insert(rows[i][2]);
    EXPECT_LE(std::abs(std::stod(rows[i][4])), 1e-3) << "test mode " << i;
  }
  EXPECT_EQ(model_modes.size(), 6u);
  for (const char* f : {"history.png", "sweeps.png", "mac_start.png", "mac.png", "sweeps.csv"})
    EXPECT_TRUE(fs::exists(dir / "out" / f)) << f;
}

TEST(UpdateLinearBeam, OneSensorFitsEveryGuessedPairOfTheStart) {
  // A newcomer's case: truth K_T 1.2e7 with the start's rz (100 N m/rad), the six bending modes
  // at one sensor (z3), K_T and rz fitted. At the start two pairs rest on a guess: test mode 3
  // between two model modes, and test mode 4 between model modes 5 and 6 (747.94 and 747.97
  // Hz, 4e-5 apart). When only the first guess was fitted both ways, the update ended
  // "converged" at rz 2129 +/- 7 % with every frequency within 0.005 %. Fitting every
  // combination, the truth fits as well (cost 3e-18 against 3e-9): rz is not identified by
  // these frequencies. It is flat at the winning pairing (sensitivity 1.2e-5) and held by the
  // flat rule, with no sigma; K_T is the truth's (noise-free frequencies, so to the optimiser's
  // tolerance; 1e-4 is a hundredth of the 1 % acceptance bound), and holding rz at 2129 instead
  // gives K_T 1.19876e7, inside K_T's 0.34 % sigma. (This update was refused as "spring.rz only
  // these pairs see" while a set no pair sees was blamed on the unconfirmed pairs; the same
  // modes made at K_T 4e7, rz 50 leave 16 pairings to fit, 2 minutes, and are not run here.)
  const fs::path dir = testing::scratch_dir("update_linear_beam_one");
  const Beam beam = build_beam(dir);
  const correlate::StiffnessSets s(beam.start, {"iwan.rivet", "spring.rz"});
  Eigen::VectorXd truth = s.initial();
  truth(0) = 1.2e7;
  std::ofstream(dir / "modes.csv") << bending_table(beam.start, s, beam.sensors, truth);
  write_one_sensor(dir);
  const testing::CommandResult u = testing::run_jointlab(fmt::format(
      "update-linear {} --modes-table {} --sensors {} --set iwan.rivet --set spring.rz --out {}",
      (dir / "model" / "model.toml").string(), (dir / "one.csv").string(),
      (dir / "sensor.csv").string(), (dir / "out").string()));
  ASSERT_EQ(u.status, 0) << u.out << u.err;
  SCOPED_TRACE(u.out);
  EXPECT_EQ(u.out.find("only these pairs see"), std::string::npos);
  EXPECT_NE(u.out.find("spring.rz is flat"), std::string::npos);
  const std::map<std::string, double> value = fitted_values(dir / "out" / "parameters.csv");
  EXPECT_TRUE(testing::Close(value.at("iwan.rivet"), 1.2e7, 1e-4));
  // rz: no standard deviation and not identifiable (parameters.csv's relative_std and
  // identifiable columns).
  int rz_rows = 0;
  for (const auto& row : read_rows(dir / "out" / "parameters.csv")) {
    if (row[0] != "spring.rz") continue;
    ++rz_rows;
    ASSERT_GE(row.size(), 6u);
    EXPECT_TRUE(row[3].empty()) << row[3];
    EXPECT_EQ(row[5], "0");
  }
  EXPECT_EQ(rz_rows, 1);
}

// A newcomer's own beam: two 0.3 m strips fully stacked with 10 rivets, two z sensors on the top
// strip off the centre line, six modes made at K_T 1.5e7, kz 5e7, rxy 300 with 0.1 % frequency
// and 1 % shape noise (one seed of a trial's six), K_T, kz and rxy fitted. spring.rxy is nearly
// flat, and the sixth test mode (1715 Hz) sits where two model modes veer: fitted each way, the
// result with rxy at 139 pairs it with one of them and the result with rxy at 5e5 with the
// other, costs 1.4e-6 and 2.9e-6, which the data cannot tell apart, and rxy is not flat at both.
// The refusal names each side's partner at its own result (the modes are numbered at different
// stiffnesses there: before, "followed to model mode 10 ... but the sensors pair it with model
// mode 10" could name one number on both sides) and the mass-weighted MAC between the two.
// About 0.3 s for the model and 0.7 s for the update.
TEST(UpdateLinearBeam, UndecidablePairsAreNamedAtEachResult) {
  const fs::path dir = testing::scratch_dir("update_linear_beam_veer");
  std::ofstream(dir / "beam.toml") << R"([strips]
length = 0.3
width = 0.025
thickness = 0.002
[mesh]
size = 0.005
[rivets]
count = 10
row_offset = 0.007
coupling_radius = 0.006
[joints]
Kt = 5.0e6
kz = 5.0e7
rxy = 500.0
rz = 50.0
[reduction]
fixed_interface_modes = 30
[[sensor]]
label = 9001
strip = 2
x = 0.02
y = 0.008
[[sensor]]
label = 9002
strip = 2
x = 0.21
y = -0.008
)";
  const testing::CommandResult b =
      testing::run_jointlab(fmt::format("build-model {} --out {} --quiet --skip-check",
                                        (dir / "beam.toml").string(), (dir / "model").string()));
  ASSERT_EQ(b.status, 0) << b.err;
  std::ofstream(dir / "sensors.csv") << "channel,dof\nt1,9001:3\nt2,9002:3\n";
  std::ofstream(dir / "modes.csv") << "mode,frequency_hz,t1,t2\n"
                                      "1,200.1970253,-4.8683692,1.8379607\n"
                                      "2,453.8769957,3.4046661,4.6886158\n"
                                      "3,790.3277186,1.9882853,-3.0945003\n"
                                      "4,848.7429187,-5.057759,-2.9876231\n"
                                      "5,1214.259129,0.73817572,-1.2889058\n"
                                      "6,1715.030372,4.855334,1.2591538\n";
  const testing::CommandResult u = testing::run_jointlab(fmt::format(
      "update-linear {} --modes-table {} --sensors {} --set iwan.rivet --set spring.kz --set "
      "spring.rxy --out {}",
      (dir / "model" / "model.toml").string(), (dir / "modes.csv").string(),
      (dir / "sensors.csv").string(), (dir / "out").string()));
  ASSERT_EQ(u.status, 2) << u.out << u.err;
  EXPECT_FALSE(fs::exists(dir / "out"));
  const size_t at = u.err.find("the pairs cannot be decided: two results pair test mode 6 (");
  ASSERT_NE(at, std::string::npos) << u.err;
  // "... with model mode A (...) at one and with model mode B (...) at the other (mass-weighted
  // MAC m between the two) (the first at spring.rxy ..., the second at spring.rxy ...)": A and B
  // differ, each the partner at its own result.
  const auto mode_after = [&](const std::string& key, size_t from) {
    const size_t k = u.err.find(key, from);
    return k == std::string::npos ? std::string() : u.err.substr(k + key.size(), 2);
  };
  const std::string first = mode_after(" with model mode ", at);
  const size_t other = u.err.find(" at one and with model mode ", at);
  ASSERT_NE(other, std::string::npos) << u.err;
  const std::string second = mode_after(" at one and with model mode ", at);
  EXPECT_NE(first, second) << u.err;
  EXPECT_NE(u.err.find(" at the other (mass-weighted MAC ", other), std::string::npos) << u.err;
  EXPECT_NE(u.err.find("(the first at spring.rxy ", other), std::string::npos) << u.err;
  EXPECT_NE(u.err.find("which the data cannot tell apart"), std::string::npos) << u.err;
  // ... and says what to add: a sensor at a model DOF no sensor reads where the two partners'
  // motions (each over its largest) differ by 0.3 or more, or the sets held (before, the line
  // ended at "the stated frequency noise)").
  EXPECT_NE(u.err.find("frequency noise): add a sensor that sees the partners apart, e.g. at "),
            std::string::npos)
      << u.err;
  EXPECT_NE(u.err.find("--hold spring.rxy=VALUE"), std::string::npos) << u.err;
}

// A wide lap plate as a newcomer builds it: two 0.3 m x 0.112 m shell strips lapped over 0.1 m,
// three rivets on the centre line, 1 cm shells (98 DOFs), eight z sensors over both strips, the
// sets started at K_T 1e7, kz 1e8, rxy 300. Its eight lowest modes made at K_T 1.3e7, kz 7e7,
// rxy 420 by an independent dense eigen-solve of the model file (numpy, /tmp/helper-57's
// truth.py: each frequency times 1 + 0.003 N(0,1), each shape entry plus 0.03 N(0,1) of the
// largest, seed 5), stated with --frequency-std 0.003. A bending and a twisting mode veer at
// 519 Hz, and the two pairings of test modes 6 and 7 fit alike (costs 1.97e-05 and 1.93e-05,
// less than 9 chi-square units apart) while the shapes tell them apart (MAC 0.998 and 0.994
// one way, 0.16 and 0.05 the other). Before, "pairs cannot be decided" (exit 2); now the shapes
// decide, with a warning saying so, and K_T and rxy come within 3 standard deviations of the
// truth (1.3012e7 +/- 1 %, 412.7 +/- 3.8 %). About 1 s.
TEST(UpdateLinearBeam, TheShapesDecideAVeeringPairTheFrequenciesCannot) {
  const fs::path dir = testing::scratch_dir("update_linear_plate_veer");
  std::string description =
      "[strips]\nlength = 0.3\nwidth = 0.112\nthickness = 0.003\noverlap = 0.1\n"
      "[mesh]\nelement = \"shell\"\nsize = 0.01\n"
      "[rivets]\npositions = [[0.22, 0.0], [0.25, 0.0], [0.28, 0.0]]\ncoupling_radius = 0.011\n"
      "[joints]\nKt = 1.0e7\nkz = 1.0e8\nrxy = 300.0\nrz = 1.0e2\n"
      "[reduction]\nfixed_interface_modes = 30\n";
  const double at[8][3] = {{1, 0.0, 0.05},  {1, 0.0, -0.05}, {1, 0.1, 0.0},   {2, 0.5, 0.05},
                           {2, 0.5, -0.05}, {2, 0.35, 0.0},  {1, 0.15, 0.05}, {2, 0.4, -0.05}};
  std::string sensors = "channel,dof\n";
  for (int i = 0; i < 8; ++i) {
    description += fmt::format("[[sensor]]\nlabel = {}\nstrip = {}\nx = {}\ny = {}\n", 9001 + i,
                               at[i][0], at[i][1], at[i][2]);
    sensors += fmt::format("s{},{}:3\n", i + 1, 9001 + i);
  }
  std::ofstream(dir / "plate.toml") << description;
  std::ofstream(dir / "sensors.csv") << sensors;
  std::ofstream(dir / "modes.csv")
      << "mode,frequency_hz,s1,s2,s3,s4,s5,s6,s7,s8\n"
         "1,60.918908,0.67968,0.71195,0.13607,0.75348,0.72269,-0.13361,-0.15004,0.13898\n"
         "2,167.516965,-0.68803,-0.73251,0.21840,0.74426,0.70158,-0.48854,0.46890,-0.31250\n"
         "3,167.446306,0.73402,-0.77070,0.01673,-0.75049,0.73165,0.01207,0.45112,0.53627\n"
         "4,289.863422,0.70487,-0.73940,-0.03869,0.73484,-0.73524,-0.00917,-0.05691,-0.33040\n"
         "5,325.311221,-0.74289,-0.69611,0.40444,-0.66805,-0.68110,0.26337,0.37520,0.46499\n"
         "6,519.055674,0.93870,0.17865,-0.36638,-0.94566,-0.20727,-0.08470,-0.20294,0.30506\n"
         "7,518.674205,-0.44569,1.04346,-0.15998,0.49104,-0.97947,0.00154,0.59359,0.35899\n"
         "8,627.270272,-0.00144,0.03011,0.00566,0.04043,-0.02296,-0.01090,0.03347,0.02705\n";
  const testing::CommandResult b =
      testing::run_jointlab(fmt::format("build-model {} --out {} --quiet --skip-check",
                                        (dir / "plate.toml").string(), (dir / "model").string()));
  ASSERT_EQ(b.status, 0) << b.err;
  const testing::CommandResult u = testing::run_jointlab(fmt::format(
      "update-linear {} --modes-table {} --sensors {} --set iwan.rivet --set spring.kz --set "
      "spring.rxy --frequency-std 0.003 --out {}",
      (dir / "model" / "model.toml").string(), (dir / "modes.csv").string(),
      (dir / "sensors.csv").string(), (dir / "out").string()));
  ASSERT_EQ(u.status, 0) << u.out << u.err;
  SCOPED_TRACE(u.out);
  EXPECT_EQ(u.out.find("linear update (least squares): converged"), 0u);
  EXPECT_NE(u.out.find("but the shapes can: kept the one that pairs test mode 6 (519.06 Hz)"),
            std::string::npos);
  // Within 3 of its standard deviations of the truth (relative_std, parameters.csv's column 4).
  for (const auto& row : read_rows(dir / "out" / "parameters.csv")) {
    if (row[0] != "iwan.rivet" && row[0] != "spring.rxy") continue;
    ASSERT_GT(row.size(), 3u);
    ASSERT_FALSE(row[3].empty()) << row[0];
    const double truth = row[0] == "iwan.rivet" ? 1.3e7 : 420;
    EXPECT_LE(std::abs(std::log(std::stod(row[2]) / truth)), 3 * std::stod(row[3])) << row[0];
  }
}

// A beam whose end bolts the frequencies bound from below only: two 0.8 m x 9 mm x 5 mm strips
// stacked (beam elements, 20 mm), 8 rivets, the end pairs a joint set of their own (iwan.bolt,
// started at 2e7; the rest iwan.rivet, started at 1e7), y and z sensors at both ends and z at
// mid-span. Its seven lowest modes made at K_T 2e7 (rivets) and 1e9 (bolts) by an independent
// dense eigen-solve of the model file (numpy, /tmp/helper-76's gen.py: each frequency times
// 1 + 0.003 N(0,1), each shape entry plus 0.03 N(0,1) of the largest, seed 8), stated with
// --frequency-std 0.003. The fit drives the bolts to 2e10, where they are flat (sensitivity
// 7e-5), from 2e7, where they are not (0.04). Before, the flat rule held them back at 2e7, and
// the rivets came out at 4.63e7 +/- 20.2 % (4.2 of those off the truth) with the misfit that
// hold made (reduced chi-square 11.2, within the noise with the bolts free) called a model-form
// error, "converged". Now the bolts stay where the fit took them, bounded from below only, and
// the rivets' profile, the bolts refitted, gives 2.04e7 +/- 8.2 %. Tolerance: the truth within
// 3 stated standard deviations. About 2 s.
TEST(UpdateLinearBeam, ASetFlatOnlyWhereTheFitTookItIsNotHeldBackAtItsStart) {
  const fs::path dir = testing::scratch_dir("update_linear_bolts_one_sided");
  std::ofstream(dir / "beam.toml") << R"([strips]
length = 0.8
width = 0.009
thickness = 0.005
[mesh]
element = "beam"
size = 0.02
[rivets]
count = 8
row_offset = 0.0
[joints]
Kt = 1.0e7
[[joint_set]]
name = "bolt"
rivets = [1, 2, 7, 8]
Kt = 2.0e7
[reduction]
fixed_interface_modes = 12
[[sensor]]
label = 9001
x = 0.0
components = ["y", "z"]
[[sensor]]
label = 9002
x = 0.43
components = ["z"]
[[sensor]]
label = 9003
x = 0.8
components = ["y", "z"]
)";
  std::ofstream(dir / "sensors.csv")
      << "channel,dof\ny1,9001:2\nz1,9001:3\nz2,9002:3\ny3,9003:2\nz3,9003:3\n";
  std::ofstream(dir / "modes.csv") << "mode,frequency_hz,y1,z1,z2,y3,z3\n"
                                      "1,73.0021,-0.9479,0.0401,0.0408,-0.9894,0.0694\n"
                                      "2,78.1675,-0.0268,-1.0286,0.5879,-0.0230,-0.9984\n"
                                      "3,191.3061,-0.0196,1.0183,0.2371,0.0432,-1.0242\n"
                                      "4,201.1458,0.9923,0.0492,-0.0108,-0.9964,0.0072\n"
                                      "5,334.0314,0.0545,-1.0466,-0.7041,0.0672,-0.9941\n"
                                      "6,395.8583,-0.9525,0.0467,-0.0259,-1.0740,-0.0371\n"
                                      "7,512.7371,0.0453,-0.9508,0.5141,0.0008,0.9738\n";
  const testing::CommandResult b =
      testing::run_jointlab(fmt::format("build-model {} --out {} --quiet --skip-check",
                                        (dir / "beam.toml").string(), (dir / "model").string()));
  ASSERT_EQ(b.status, 0) << b.err;
  const testing::CommandResult u = testing::run_jointlab(
      fmt::format("update-linear {} --modes-table {} --sensors {} --set iwan.rivet --set iwan.bolt "
                  "--frequency-std 0.003 --out {}",
                  (dir / "model" / "model.toml").string(), (dir / "modes.csv").string(),
                  (dir / "sensors.csv").string(), (dir / "out").string()));
  ASSERT_EQ(u.status, 0) << u.out << u.err;
  SCOPED_TRACE(u.out);
  EXPECT_EQ(u.out.find("linear update (least squares): converged"), 0u);
  EXPECT_EQ(u.out.find("model-form error"), std::string::npos);
  EXPECT_NE(u.out.find("iwan.bolt: the frequencies bound it from below only: the fit took it up "
                       "to 2e+10"),
            std::string::npos);
  // How stiff, not only "stiff": the value written is the fit's (the range's bound), and the
  // warning states the lowest value the frequencies allow, 3 standard deviations down the
  // profile (3.05e8): the truth (1e9) lies above it, and it lies above the start the
  // frequencies see (2e7).
  const std::string down = "they allow it down to ";
  const size_t at = u.out.find(down);
  ASSERT_NE(at, std::string::npos);
  const double lowest = std::stod(u.out.substr(at + down.size()));
  EXPECT_LE(lowest, 1e9);
  EXPECT_GT(lowest, 2e7);
  // At the range's bound the frequencies no longer see it: a wider range moves it, not the fit
  // (it was told to widen the bounds).
  EXPECT_NE(u.out.find("iwan.bolt ends at its upper bound 2e+10, where the frequencies no longer "
                       "see it"),
            std::string::npos);
  EXPECT_EQ(u.out.find("iwan.bolt ends at its upper bound 2e+10: widen the bounds"),
            std::string::npos);
  bool rivet = false;
  for (const auto& row : read_rows(dir / "out" / "parameters.csv")) {
    ASSERT_GT(row.size(), 5u);
    if (row[0] == "iwan.bolt") {
      EXPECT_TRUE(row[3].empty());  // no standard deviation
      EXPECT_EQ(row[5], "0");       // not identifiable
    }
    if (row[0] != "iwan.rivet") continue;
    rivet = true;
    ASSERT_FALSE(row[3].empty());
    EXPECT_LE(std::abs(std::log(std::stod(row[2]) / 2e7)), 3 * std::stod(row[3]));
  }
  EXPECT_TRUE(rivet);

  // The same frequencies stated to 0.1 % (three times too small): reduced chi-square 4.83 over
  // 6, so the sigmas rest on the scatter and their 3 standard deviations are Student's t's, a
  // rise of 16 (the rivets' line says so). The bolts' lower limit is 3 standard deviations down
  // the same profile: before, it was walked to a rise of 9 alone (3.1e8, where the rivets' sigma
  // used 16); now to 16, 8.41e7, below the truth 1e9 as before.
  const testing::CommandResult w = testing::run_jointlab(
      fmt::format("update-linear {} --modes-table {} --sensors {} --set iwan.rivet --set iwan.bolt "
                  "--frequency-std 0.001 --out {}",
                  (dir / "model" / "model.toml").string(), (dir / "modes.csv").string(),
                  (dir / "sensors.csv").string(), (dir / "out_understated").string()));
  ASSERT_EQ(w.status, 0) << w.out << w.err;
  EXPECT_NE(w.out.find("reaches Student's t's 3 standard deviations, a rise of 16"),
            std::string::npos)
      << w.out;
  const size_t wat = w.out.find(down);
  ASSERT_NE(wat, std::string::npos) << w.out;
  EXPECT_LE(std::stod(w.out.substr(wat + down.size())), 1e9) << w.out;
  EXPECT_NE(w.out.find("the other sets fitted again, rises by 16: 3 standard deviations, "
                       "Student's t's: the sigmas rest on the scatter"),
            std::string::npos)
      << w.out;
}

}  // namespace
}  // namespace jointlab
