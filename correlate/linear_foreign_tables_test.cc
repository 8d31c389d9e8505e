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
#include "jointlab/correlate/linear_signs.h"
#include "jointlab/correlate/linear_update.h"
#include "jointlab/correlate/measured_data.h"
#include "jointlab/correlate/mode_tracking.h"
#include "jointlab/correlate/sensors.h"
#include "jointlab/correlate/two_chain.h"
#include "jointlab/model/fe/model_builder.h"
#include "jointlab/model/linear_modes.h"
#include "jointlab/model/model_file.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::correlate {
namespace {

namespace fs = std::filesystem;

// A sensors text read at the edge (data::parse_sensors_file) and resolved against `model`.
std::vector<Sensor> parse_sensors(const std::string& text, const std::string& name,
                                  const model::Model& model) {
  return sensors_of(data::parse_sensors_file(text, name), model);
}

// A modes table read at the edge (data::read_modes_table against the sensors' channels) and
// realised (measured_modes), its mode numbers into `numbers` (if given).
MeasuredModes read_table_modes(const fs::path& path, const std::vector<Sensor>& sensors,
                               std::vector<int>* numbers) {
  const data::ModesTable table = data::read_modes_table(path, channels_of(sensors));
  if (numbers) *numbers = table.modes;
  return measured_modes(table, sensors);
}

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

// A table of frequencies alone, in rad/s under frequency_hz: with no shape to pair by, the
// twenty-mass chains' four lowest modes (ka started at twice the truth, ka and kb fitted) read
// as Hz were refused "the pairs cannot be decided", the unit never named (the refit that names
// it where the fit leaves scatter cannot confirm it here: the same table in Hz can be as
// undecidable, as the example beam's six bending modes are with its four sets). Now the refusal
// names rad/s first: divided by 2 pi each mode has a visible model mode of its own at the start,
// and read as Hz the table's lowest lies above model modes it leaves unmeasured. No false alarm
// on tables in Hz (each checked where the pairs were undecided): the chains' modes, those with a
// mode missing or a 5 Hz fixture row, and the example beam's six bending modes (beam elements,
// truth K_T 4e7 and rz 50; its table in rad/s is named). About 0.4 s, most of it the beam's build.
TEST(ModesTableFromAnotherTool, FrequenciesAloneInRadPerSecondAreNamedWhereThePairsAreUndecided) {
  TwoChainParameters truth;
  truth.n = 10;
  const model::Model m = two_chain_structure(truth);
  const std::vector<Sensor> sensors = chain_sensors(truth.n);
  MeasuredModes hz = chain_modes(m, sensors, 4);
  hz.shapes.setZero();  // a table of `mode,frequency_hz` alone
  TwoChainParameters begin = truth;
  begin.ka *= 2;
  const model::Model start = two_chain_structure(begin);
  const std::vector<std::string> sets = {"spring.ka", "spring.kb"};
  MeasuredModes rad = hz;
  rad.frequency_hz *= 2 * std::numbers::pi;
  // Frequencies alone: named before any fit (no iteration), by the same rule.
  LinearUpdateSummary before;
  update_linear(start, sets, sensors, rad, {}, &before);
  ASSERT_EQ(before.status, LinearUpdateStatus::kShapesRefused) << before.report();
  EXPECT_EQ(before.iterations, 0);
  EXPECT_TRUE(before.history.empty());
  const std::string first = linear_refusal(before, {}, "modes.csv");
  EXPECT_EQ(
      first.find("modes.csv: the frequencies look like angular frequencies (rad/s) read as Hz: "
                 "divided by 2 pi, each measured mode has a model mode of its own at the start"),
      0u)
      << first;
  EXPECT_NE(first.find("give frequency_hz in Hz (rad/s divided by 2 pi); decided before any fit, "
                       "as a table of frequencies alone (if they are in Hz, give each mode's "
                       "entry at one sensor"),
            std::string::npos)
      << first;
  // Each mode's entry at one sensor pairs by frequency alone as before and is fitted: its pairs
  // undecided, the refusal names the unit after the fit.
  MeasuredModes one = rad;
  one.shapes.row(0).setConstant(1.0);
  LinearUpdateSummary s;
  update_linear(start, sets, sensors, one, {}, &s);
  ASSERT_EQ(s.status, LinearUpdateStatus::kAmbiguous) << s.report();
  const std::string why = linear_refusal(s, {}, "modes.csv");
  EXPECT_EQ(
      why.find("modes.csv: the frequencies look like angular frequencies (rad/s) read as Hz: "
               "divided by 2 pi, each measured mode has a model mode of its own at the start"),
      0u)
      << why;
  EXPECT_NE(why.find("give frequency_hz in Hz (rad/s divided by 2 pi); were they in Hz, the pairs "
                     "cannot be decided: "),
            std::string::npos)
      << why;
  EXPECT_EQ(why.find('\n'), std::string::npos) << why;

  // A fit beyond the noise that the refit divided by 2 pi does not better from the start (six
  // chains of six masses, three sets): before, "converged" with 3 of 6 modes paired and a
  // reduced chi-square of 453, the unit never named; now a warning names it.
  TwoChainParameters six;
  TwoChainParameters six_begin = six;
  six_begin.ka *= 2;
  const std::vector<Sensor> six_sensors = chain_sensors(six.n);
  MeasuredModes six_rad = chain_modes(two_chain_structure(six), six_sensors, 6);
  six_rad.shapes.setZero();
  six_rad.frequency_hz *= 2 * std::numbers::pi;
  LinearUpdateSummary f;
  update_linear(two_chain_structure(six_begin), {"spring.ka", "spring.kb", "spring.kflat"},
                six_sensors, six_rad, {}, &f);
  const std::string said = f.report() + linear_refusal(f, {}, "modes.csv");
  EXPECT_NE(said.find("the frequencies look like angular frequencies (rad/s) read as Hz"),
            std::string::npos)
      << said;

  // Tables in Hz, judged as if their pairs were undecided at the start.
  const auto named = [&](const model::Model& model, const std::vector<std::string>& names,
                         const std::vector<Sensor>& at, const MeasuredModes& table) {
    const StiffnessSets stiffness(model, names);
    LinearUpdateSummary u;
    u.status = LinearUpdateStatus::kAmbiguous;
    u.start = evaluate_linear(stiffness, model, at, table, stiffness.initial(), 0.6, 0.5);
    return detail::undecided_units(table, {}, u);
  };
  EXPECT_NE(named(start, sets, sensors, rad), "");
  EXPECT_EQ(named(start, sets, sensors, hz), "");
  EXPECT_EQ(named(start, sets, sensors, hz.columns({0, 2, 3})), "");
  MeasuredModes fixture = hz;
  fixture.frequency_hz.conservativeResize(5);
  fixture.frequency_hz(4) = 5;
  fixture.shapes.conservativeResize(Eigen::NoChange, 5);
  fixture.shapes.col(4).setZero();
  EXPECT_EQ(named(start, sets, sensors, fixture), "");

  // The example beam with beam elements (0.3 s to build): its six bending modes in Hz, at the
  // five z sensors, with their shapes and without.
  model::fe::RivetedBeamDescription d = model::fe::read_riveted_beam_description(
      fs::path(jointlab::testing::source_dir()) / "examples" / "riveted_beam" / "description.toml");
  d.shell = false;
  const fs::path dir = jointlab::testing::scratch_folder("jointlab_foreign_tables_beam");
  model::fe::write_model_directory(dir, model::fe::build_reduced_model(d, {}));
  const model::Model beam = model::read_model(dir / "model.toml");
  const std::vector<Sensor> z = parse_sensors(
      "channel,dof\nz1,9001:3\nz2,9002:3\nz3,9003:3\nz4,9004:3\nz5,9005:3\n", "sensors.csv", beam);
  const std::vector<std::string> four = {"iwan.rivet", "spring.kz", "spring.rxy", "spring.rz"};
  const StiffnessSets bs(beam, four);
  Eigen::VectorXd at = bs.initial();
  at(0) = 4e7;
  at(3) = 50;
  const ElasticModes bm = elastic_modes(beam.mass, bs.stiffness(at));
  const Eigen::MatrixXd shapes = shapes_at_sensors(z, bm.shapes);
  std::vector<Eigen::Index> bending;
  for (Eigen::Index j = 0; j < shapes.cols() && bending.size() < 6; ++j)
    if (shapes.col(j).squaredNorm() > 1) bending.push_back(j);
  ASSERT_EQ(bending.size(), 6u);
  MeasuredModes table;
  table.frequency_hz.resize(6);
  table.shapes.resize(5, 6);
  for (int i = 0; i < 6; ++i) {
    table.frequency_hz(i) = bm.frequency_hz(bending[static_cast<size_t>(i)]);
    table.shapes.col(i) = shapes.col(bending[static_cast<size_t>(i)]).cast<std::complex<double>>();
  }
  EXPECT_EQ(named(beam, four, z, table), "");
  MeasuredModes alone = table;
  alone.shapes.setZero();
  EXPECT_EQ(named(beam, four, z, alone), "");
  EXPECT_EQ(named(beam, four, z, alone.columns({0, 1, 3, 4, 5})), "");
  alone.frequency_hz *= 2 * std::numbers::pi;
  EXPECT_NE(named(beam, four, z, alone), "");
  // Before any fit too, from the model's start (units_before_fit: the docs' case, refused in
  // 0.05 s rather than after 9 min of fitting); the same table in Hz is not named there.
  LinearEvaluation early;
  EXPECT_NE(detail::units_before_fit(beam, four, z, alone, {}, early), "");
  alone.frequency_hz /= 2 * std::numbers::pi;
  EXPECT_EQ(detail::units_before_fit(beam, four, z, alone, {}, early), "");
  // A lab's table of higher modes alone, truly in Hz, is not judged before the fit: two modes
  // (their ratio alone says little), or modes that divided by 2 pi lie over 25 % from the start's
  // (here up to 40 %: the fit then pairs them as Hz, or names rad/s after it from the misfit).
  for (const std::vector<Eigen::Index>& upper :
       {std::vector<Eigen::Index>{3, 5}, std::vector<Eigen::Index>{2, 4},
        std::vector<Eigen::Index>{3, 4, 5}}) {
    EXPECT_EQ(detail::units_before_fit(beam, four, z, alone.columns(upper), {}, early), "")
        << upper.size() << " modes from " << upper.front() + 1;
  }
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
  const MeasuredModes plain = read_table_modes(
      write("plain.csv", "mode,frequency_hz,z1,z2,z3\n1,57.9,0.5,-0.25,1\n2,120,1,0.5,-0.75\n"),
      sensors, nullptr);
  const MeasuredModes extra = read_table_modes(
      write("extra.csv",
            "mode,frequency_hz,Damping [%],z1,z2,z3,damping_ratio,MPC,mpd (deg)\n"
            "1,57.9,0.12,0.5,-0.25,1,0.0012,0.998,1.5\n2,120,0.2,1,0.5,-0.75,0.002,0.97,4\n"),
      sensors, nullptr);
  // Exact: the same cells parse to the same doubles, so any difference is a column misread.
  ASSERT_EQ(extra.frequency_hz.size(), 2);
  EXPECT_EQ(extra.frequency_hz, plain.frequency_hz);
  EXPECT_EQ(extra.shapes, plain.shapes);
  const std::string unknown = jointlab::testing::input_error_of([&] {
    read_table_modes(write("unknown.csv", "mode,frequency_hz,z1,acc4\n1,57.9,1,2\n"), sensors,
                     nullptr);
  });
  EXPECT_NE(unknown.find("unknown.csv:1: column 'acc4' is not a sensor channel (the sensors file "
                         "has 3 channels: z1, z2, z3)"),
            std::string::npos)
      << unknown;
  const std::string rad = jointlab::testing::input_error_of([&] {
    read_table_modes(write("rad.csv", "mode,frequency_rad_s,z1\n1,363.8,1\n"), sensors, nullptr);
  });
  EXPECT_NE(rad.find("rad.csv:1: column 2 'frequency_rad_s': frequencies are read in Hz only, "
                     "under frequency_hz: give them so (rad/s divided by 2 pi)"),
            std::string::npos)
      << rad;
}

// Frequency headers as test-modal tools write them: 'Mode,Frequency [Hz],Damping [%]',
// 'Freq (Hz)', 'f_Hz' and 'Frequency [kHz]' were refused ("the header must begin with
// mode,frequency_hz"); the unit they name is explicit, so they are read, kHz times 1000 (exact:
// the same doubles as the plain table, 0.0579 kHz to within one rounding). A frequency without
// a unit, in a unit not read, in rad/s, after the mode column or beside a decimal comma is
// refused in one line naming the file, the line and the column.
TEST(ModesTableFromAnotherTool, FrequencyHeadersWithTheirUnitAreRead) {
  const fs::path d = jointlab::testing::scratch_folder("jointlab_foreign_headers_test");
  const std::vector<Sensor> sensors{{"z1", 1, 1.0}, {"z2", 2, 1.0}};
  const auto read = [&](const std::string& header, const std::string& rows) {
    std::ofstream(d / "t.csv") << header << "\n" << rows;
    return read_table_modes(d / "t.csv", sensors, nullptr);
  };
  const std::string rows = "1,57.9,0.5,1\n2,120,1,-0.5\n";
  const MeasuredModes plain = read("mode,frequency_hz,z1,z2", rows);
  for (const std::string f : {"Frequency [Hz]", "Freq (Hz)", "f_Hz", "Frequency_Hz", "FREQ [hz]",
                              "frequency_hz [Hz]", "Natural frequency (Hz)"}) {
    const MeasuredModes m = read("Mode," + f + ",z1,z2", rows);
    EXPECT_EQ(m.frequency_hz, plain.frequency_hz) << f;
    EXPECT_EQ(m.shapes, plain.shapes) << f;
  }
  // The mode column as test-modal tools head it (before, `Mode #` was refused: "column 1 'Mode
  // #' is not 'mode'").
  for (const std::string mode :
       {"Mode #", "Mode#", "MODE NO.", "Mode No", "mode_nr", "Mode Number"}) {
    const MeasuredModes m = read(mode + ",frequency_hz,z1,z2", rows);
    EXPECT_EQ(m.frequency_hz, plain.frequency_hz) << mode;
    EXPECT_EQ(m.shapes, plain.shapes) << mode;
  }
  const MeasuredModes damping =
      read("Mode,Frequency [Hz],Damping [%],z1,z2", "1,57.9,0.3,0.5,1\n2,120,0.2,1,-0.5\n");
  EXPECT_EQ(damping.frequency_hz, plain.frequency_hz);
  const MeasuredModes k = read("mode,Frequency [kHz],z1,z2", "1,0.0579,0.5,1\n2,0.12,1,-0.5\n");
  EXPECT_TRUE(k.frequency_hz.isApprox(plain.frequency_hz, 1e-15)) << k.frequency_hz.transpose();
  const auto error = [&](const std::string& header, const std::string& row) {
    return jointlab::testing::input_error_of([&] { read(header, row); });
  };
  const std::string file = (d / "t.csv").string();
  const std::vector<std::pair<std::string, std::string>> refused = {
      {"mode,Frequency",
       "1: column 2 'Frequency': a frequency needs its unit: write "
       "frequency_hz, or the unit in brackets ('Frequency [Hz]', 'Frequency "
       "[kHz]')"},
      {"mode,Frequency [cpm]",
       "1: column 2 'Frequency [cpm]': unit 'cpm' is not read: give the frequencies in Hz "
       "(frequency_hz) or kHz"},
      {"mode,frequency_hz [kHz]",
       "1: column 2 'frequency_hz [kHz]': unit 'kHz' refused: frequency_hz is in Hz ([Hz] or no "
       "unit)"},
      {"mode,Frequency (rad/s)",
       "1: column 2 'Frequency (rad/s)': frequencies are read in Hz "
       "only, under frequency_hz: give them so (rad/s divided by 2 pi)"},
      {"frequency_hz,mode",
       "1: the header must begin with mode,frequency_hz (or a frequency "
       "with its unit, 'Frequency [Hz]'); it begins 'frequency_hz,mode': "
       "put the mode column first"},
      {"mode,z1,frequency_hz",
       "1: the header must begin with mode,frequency_hz (or a frequency "
       "with its unit, 'Frequency [Hz]'); it begins 'mode,z1', column 2 "
       "'z1' names no frequency"},
      // update-linear's own output given back (it was told only "column 1 'measured' is not
      // 'mode'").
      {"measured,frequency_hz,model_mode,model_frequency_hz,error,mac",
       "1: the header must begin with mode,frequency_hz (or a frequency with its unit, "
       "'Frequency [Hz]'); it begins 'measured,frequency_hz': this is the modes.csv "
       "update-linear writes (measured against model modes), not a modes table; give "
       "--measured DIR or a table of mode, frequency_hz and one shape column per sensor"},
  };
  for (const auto& [header, message] : refused)
    EXPECT_EQ(error(header, "1,57.9\n"), file + ":" + message) << header;
  // A European export: ';' between the cells is read, a decimal comma is named.
  EXPECT_EQ(read("mode;frequency_hz;z1;z2", "1;57.9;0.5;1\n2;120;1;-0.5\n").frequency_hz,
            plain.frequency_hz);
  EXPECT_EQ(error("mode;frequency_hz", "1;57,9\n"),
            file +
                ":2: frequency_hz '57,9' is not a number (a decimal comma: write 57.9 with a "
                "decimal point; ';' or tab may still separate the cells)");
  // Before, a shape entry with a decimal comma was named only "not a number (real, or complex
  // as ...)", where the frequencies were whole numbers.
  EXPECT_EQ(error("mode;frequency_hz;z1;z2", "1;58;0,5;1\n"),
            file +
                ":2: shape entry '0,5' of column 'z1' is not a number (a decimal comma: write "
                "0.5 with a decimal point; ';' or tab may still separate the cells)");
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
