#include "jointlab/data/stepped_sine.h"

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <numbers>

#include <gtest/gtest.h>
#include <matio.h>

#include "jointlab/tests/test_util.h"

namespace jointlab::data {
namespace {

using testing::input_error_of;

const char kTable[] =
    "# test: bench\n"
    "# control: response\n"
    "# level: 2 g\n"
    "frequency_hz,force [N],response [g],phase [deg]\n"
    "79.2,0.5,2,-10\n"
    "79.0,0.6,2,-5\n"  // out of order: sorted on reading
    "79.4,0.4,2,-30\n"
    "79.6,0.3,2,-90\n"
    "79.8,0.4,2,-150\n";

TEST(SteppedSineCsv, ReadsOneTableWithUnitsAndMetadata) {
  const auto tables = parse_stepped_sine_csv(kTable, "t.csv");
  ASSERT_EQ(tables.size(), 1u);
  const SteppedSineTable& t = tables[0];
  EXPECT_EQ(t.control, SineControl::kResponse);
  EXPECT_EQ(t.response_quantity, Quantity::kAcceleration);
  EXPECT_EQ(t.label, "level 2 g");
  EXPECT_EQ(t.index, 1);
  EXPECT_EQ(t.metadata.at("test"), "bench");
  ASSERT_EQ(t.size(), 5);
  EXPECT_EQ(t.frequency_hz(0), 79.0);
  EXPECT_EQ(t.force(0), 0.6);
  EXPECT_DOUBLE_EQ(t.response(0), 2 * 9.80665);  // g to m/s^2
  EXPECT_DOUBLE_EQ(t.phase_rad(3), -std::numbers::pi / 2);
}

TEST(SteppedSineCsv, SplitsLevelsAndControlsByColumn) {
  const std::string text =
      "level;control;frequency [Hz];force [N];response [mm/s];phase [rad]\n"
      "a;force;1;1;1;0\na;force;2;1;1;0\na;force;3;1;1;0\na;force;4;1;1;0\na;force;5;1;1;0\n"
      "b;response;1;2;1;0\nb;response;2;2;1;0\nb;response;3;2;1;0\nb;response;4;2;1;0\n"
      "b;response;5;2;1;0\n";
  const auto tables = parse_stepped_sine_csv(text, "t.csv");
  ASSERT_EQ(tables.size(), 2u);
  EXPECT_EQ(tables[0].control, SineControl::kForce);
  EXPECT_EQ(tables[1].control, SineControl::kResponse);
  EXPECT_EQ(tables[1].label, "level b");
  EXPECT_EQ(tables[1].index, 2);
  EXPECT_EQ(tables[1].response_quantity, Quantity::kVelocity);
  EXPECT_DOUBLE_EQ(tables[1].response(0), 1e-3);
}

TEST(SteppedSineCsv, WriteThenReadGivesTheSameTables) {
  const auto tables = parse_stepped_sine_csv(kTable, "t.csv");
  const auto path = testing::scratch_path("stepped_sine_test", "round.csv");
  write_stepped_sine_csv(path, tables, {"source: test"});
  const auto back = read_stepped_sine(path);
  ASSERT_EQ(back.size(), 1u);
  EXPECT_EQ(back[0].control, SineControl::kResponse);
  for (Eigen::Index i = 0; i < 5; ++i) {
    EXPECT_TRUE(testing::Close(back[0].response(i), tables[0].response(i), 1e-9));
    EXPECT_TRUE(testing::Close(back[0].phase_rad(i), tables[0].phase_rad(i), 1e-9, 1e-12));
  }
}

TEST(SteppedSineCsv, BadInputNamesFileAndLine) {
  auto err = [](const std::string& text) {
    return input_error_of([&] { parse_stepped_sine_csv(text, "s.csv"); });
  };
  const std::string head =
      "# control: force\nfrequency_hz,force [N],response [m/s^2],phase [deg]\n";
  const std::string rows = "1,1,1,0\n2,1,1,0\n3,1,1,0\n4,1,1,0\n";
  EXPECT_NE(err(head + rows + "5,1,x,0\n").find("s.csv:7: column 'response [m/s^2]': 'x'"),
            std::string::npos);
  EXPECT_NE(err(head + rows + "5,-1,1,0\n").find("s.csv:7: force amplitude -1"), std::string::npos);
  EXPECT_NE(err(head + rows + "4,1,1,0\n").find("s.csv:7: frequency 4 Hz appears twice"),
            std::string::npos);
  EXPECT_NE(err(head + rows).find("4 frequencies; a stepped-sine table needs at least 5"),
            std::string::npos);
  EXPECT_NE(err(head + rows + "5,1,1\n").find("s.csv:7: 3 fields where the header has 4"),
            std::string::npos);
  EXPECT_NE(err("frequency_hz,force [N],response [m/s^2],phase [deg]\n" + rows + "5,1,1,0\n")
                .find("control not given"),
            std::string::npos);
  EXPECT_NE(err("# control: both\n").find("s.csv:1: control 'both'"), std::string::npos);
  EXPECT_NE(err("# control: force\nfrequency_hz,force [N],response [m/s^2],phase [grad]\n")
                .find("s.csv:2: column 'phase': unit 'grad' is not deg or rad"),
            std::string::npos);
  EXPECT_NE(err("# control: force\nfrequency_hz,force [N],response,phase [deg]\n")
                .find("column 'response' has no unit"),
            std::string::npos);
  // A frequency column in any unit but Hz (it was read as Hz, 2 pi too high for rad/s).
  EXPECT_NE(err("# control: force\nfrequency_hz [rad/s],force [N],response [m/s^2],phase [deg]\n")
                .find("s.csv:2: column 'frequency_hz': unit 'rad/s' is not Hz"),
            std::string::npos);
  EXPECT_NE(err("# control: force\nfrequency [kHz],force [N],response [m/s^2],phase [deg]\n")
                .find("s.csv:2: column 'frequency': unit 'kHz' is not Hz"),
            std::string::npos);
  EXPECT_EQ(parse_stepped_sine_csv("# control: force\nfrequency_hz [Hz],force [N],response "
                                   "[m/s^2],phase [deg]\n" +
                                       rows + "5,1,1,0\n",
                                   "s.csv")[0]
                .frequency_hz(4),
            5.0);
  EXPECT_NE(
      err("# control: force\nfrequency_hz,force [N],phase [deg]\n").find("no 'response' column"),
      std::string::npos);
  EXPECT_NE(err("").find("s.csv: empty file"), std::string::npos);
  // A response without a unit is SI of the quantity given.
  const auto t = parse_stepped_sine_csv(
      "# control: force\nfrequency_hz,force [N],response,phase [deg]\n" + rows + "5,1,1,0\n",
      "s.csv", Quantity::kDisplacement);
  EXPECT_EQ(t[0].response_quantity, Quantity::kDisplacement);
}

// A response or force column whose header says it was measured RMS or peak to peak. Before, a
// header 'response_rms [m/s^2]' was refused only as "no 'response' column", and renamed as told
// its values were read zero to peak: the backbone's amplitudes came out 0.707 times the truth (a
// table of 2 m/s^2 held, written as 1.414 RMS, gave points at 1.414), and F_S with them, which no
// fit can tell. Now each such header names its factor first, in the backbone tables' words
// (amplitude_measure.h); a column measured zero to peak ('acc_peak') or one beside the 'response'
// column read is left as before.
// The message a table of response control with header line `header` is refused with.
std::string header_error(const std::string& header) {
  return input_error_of([&] { parse_stepped_sine_csv("# control: response\n" + header, "s.csv"); });
}

// The factors the amplitude-measure messages name (amplitude_measure.h).
const std::string kRmsFix =
    "multiply its values by sqrt(2) = 1.4142 (an amplitude is read zero to peak, a sine's RMS "
    "times sqrt(2); read as it is, F_S comes out 0.707 times the truth)";
const std::string kHalfFix =
    "halve its values (an amplitude is read zero to peak; peak-to-peak values read as they are "
    "give F_S twice the truth)";

TEST(SteppedSineCsv, AResponseMeasuredRmsOrPeakToPeakIsToldItsFactor) {
  const std::string force_rms =
      "multiply its values by sqrt(2) = 1.4142 (a force amplitude is read zero to peak)";
  // In the name: both columns named, each with its factor.
  EXPECT_EQ(header_error("frequency_hz,force_rms [N],response_rms [m/s^2],phase [deg]\n"),
            "s.csv:2: column 2 'force_rms [N]': " + force_rms +
                ", then rename it 'force [N]'; column 3 'response_rms [m/s^2]': " + kRmsFix +
                ", then rename it 'response [m/s^2]'");
  EXPECT_EQ(header_error("frequency_hz,force [N],acc_pp [g],phase [deg]\n"),
            "s.csv:2: column 3 'acc_pp [g]': " + kHalfFix + ", then rename it 'response [g]'");
  EXPECT_EQ(header_error("frequency_hz,Force RMS (N),response [m/s^2],phase [deg]\n"),
            "s.csv:2: column 2 'Force RMS (N)': " + force_rms + ", then rename it 'force [N]'");
  // Beside the unit, and after it.
  EXPECT_EQ(header_error("frequency_hz,force [N],response [m/s^2 RMS],phase [deg]\n"),
            "s.csv:2: column 'response [m/s^2 RMS]': 'RMS' says how it was measured, not a unit: " +
                kRmsFix + ", then write 'response [m/s^2]'");
  EXPECT_EQ(header_error("frequency_hz,force [pk-pk N],response [m/s^2],phase [deg]\n"),
            "s.csv:2: column 'force [pk-pk N]': 'pk-pk' says how it was measured, not a unit: "
            "halve its values (a force amplitude is read zero to peak), then write 'force [N]'");
  EXPECT_EQ(header_error("frequency_hz,force [N],response [mm/s] (peak-to-peak),phase [deg]\n"),
            "s.csv:2: column 3 'response [mm/s] (peak-to-peak)': " + kHalfFix +
                ", then write 'response [mm/s]'");
  // Zero to peak by name: no factor, the missing column as before.
  EXPECT_EQ(header_error("frequency_hz,force [N],acc_peak [g],phase [deg]\n"),
            "s.csv:2: no 'response' column (need frequency_hz, force [N], response [unit], phase "
            "[deg|rad])");
  // An RMS column beside the response read is one more column, ignored.
  const std::string rows = "1,1,1,0,0.7\n2,1,1,0,0.7\n3,1,1,0,0.7\n4,1,1,0,0.7\n5,1,1,0,0.7\n";
  const auto t = parse_stepped_sine_csv(
      "# control: response\nfrequency_hz,force [N],response [m/s^2],phase [deg],response_rms "
      "[m/s^2]\n" +
          rows,
      "s.csv");
  EXPECT_EQ(t[0].response(0), 1.0);
}

// A measure joined to its unit ('[grms]', '[g_rms]', '[Npp]'), peak to peak written 'p-p' or
// 'pk-to-pk', and a unit in round brackets beside the measure ('Response (g RMS)'). Before,
// '[grms]' and '[N p-p]' were refused only as no unit (no factor), and '[g_rms]' and 'Response
// (g RMS)' were told to write 'response' without the 'g': followed with --quantity, values in g
// were read as m/s^2 (F_S 9.81 times off) or, zero to peak, 0.707 times the truth. Now each names
// its factor and keeps its unit.
TEST(SteppedSineCsv, AMeasureJoinedToItsUnitIsToldItsFactorAndKeepsTheUnit) {
  EXPECT_EQ(header_error("frequency_hz,force [N],response [grms],phase [deg]\n"),
            "s.csv:2: column 'response [grms]': 'rms' says how it was measured, not a unit: " +
                kRmsFix + ", then write 'response [g]'");
  EXPECT_EQ(header_error("frequency_hz,force [N],response [g_rms],phase [deg]\n"),
            "s.csv:2: column 'response [g_rms]': 'rms' says how it was measured, not a unit: " +
                kRmsFix + ", then write 'response [g]'");
  EXPECT_EQ(header_error("frequency_hz,force [N],response [mm/s pk-to-pk],phase [deg]\n"),
            "s.csv:2: column 'response [mm/s pk-to-pk]': 'pk-to-pk' says how it was measured, "
            "not a unit: " +
                kHalfFix + ", then write 'response [mm/s]'");
  EXPECT_EQ(header_error("frequency_hz,force [N p-p],response [g],phase [deg]\n"),
            "s.csv:2: column 'force [N p-p]': 'p-p' says how it was measured, not a unit: halve "
            "its values (a force amplitude is read zero to peak), then write 'force [N]'");
  EXPECT_EQ(header_error("frequency_hz,force [Npp],response [g],phase [deg]\n"),
            "s.csv:2: column 'force [Npp]': 'pp' says how it was measured, not a unit: halve "
            "its values (a force amplitude is read zero to peak), then write 'force [N]'");
  EXPECT_EQ(header_error("frequency_hz,force [N],Response (g RMS),phase [deg]\n"),
            "s.csv:2: column 3 'Response (g RMS)': " + kRmsFix + ", then rename it 'response [g]'");
  EXPECT_EQ(header_error("frequency_hz,force [N],resp [g rms],phase [deg]\n"),
            "s.csv:2: column 3 'resp [g rms]': " + kRmsFix + ", then rename it 'response [g]'");
  // A unit the reader does not take is kept too, for the next refusal to name ('M/S^2').
  EXPECT_EQ(header_error("frequency_hz,force [N],response [M/S^2 rms],phase [deg]\n"),
            "s.csv:2: column 'response [M/S^2 rms]': 'rms' says how it was measured, not a "
            "unit: " +
                kRmsFix + ", then write 'response [M/S^2]'");
}

// A level labelled RMS or peak to peak ('# level: 1.414 m/s^2 RMS', a level column '2 g pk-pk').
// Before, the label was kept as a label and the columns read zero to peak: a sweep held at 2
// m/s^2, written 1.414 RMS with the label saying so, gave its backbone point at 0.707 times the
// amplitude (F_S with it), without a word. Now refused on the label's line with the factor.
TEST(SteppedSineCsv, ALevelLabelledRmsOrPeakToPeakIsRefusedWithTheFactor) {
  const std::string rows = "1,1,1,0\n2,1,1,0\n3,1,1,0\n4,1,1,0\n5,1,1,0\n";
  const std::string header = "frequency_hz,force [N],response [m/s^2],phase [deg]\n";
  EXPECT_EQ(input_error_of([&] {
              parse_stepped_sine_csv(
                  "# control: response\n# level: 1.414 m/s^2 RMS\n" + header + rows, "s.csv");
            }),
            "s.csv:2: level '1.414 m/s^2 RMS' says it was measured RMS, but force and response "
            "are read zero to peak: where their columns hold RMS values, multiply them by sqrt(2) "
            "= 1.4142 (read as they are, F_S comes out 0.707 times the truth); then, or where "
            "they are zero to peak already, write the level without 'RMS'");
  EXPECT_EQ(input_error_of([&] {
              parse_stepped_sine_csv(
                  "# control: response\nfrequency_hz,force [N],response [g],phase [deg],level\n"
                  "1,1,1,0,2 g pk-pk\n",
                  "s.csv");
            }),
            "s.csv:3: level '2 g pk-pk' says it was measured peak-to-peak, but force and response "
            "are read zero to peak: where their columns hold peak-to-peak values, halve them "
            "(read as they are, F_S comes out twice the truth); then, or where they are zero to "
            "peak already, write the level without 'pk-pk'");
  // A level without a measure is read as before.
  EXPECT_EQ(
      parse_stepped_sine_csv("# control: response\n# level: 2 m/s^2\n" + header + rows, "s.csv")[0]
          .label,
      "level 2 m/s^2");
}

TEST(SteppedSineMat, ReadsTheBrakeReussStructLayout) {
  const auto tables = read_stepped_sine(
      testing::source_dir() + "/data/examples/brake-reuss-beam/forced_frequency_responses.mat");
  ASSERT_EQ(tables.size(), 12u);
  int force = 0, response = 0;
  for (const SteppedSineTable& t : tables) {
    (t.control == SineControl::kForce ? force : response)++;
    EXPECT_EQ(t.size(), 41);
    EXPECT_EQ(t.response_quantity, Quantity::kAcceleration);
    EXPECT_GE(t.frequency_hz(0), 79.0);
    EXPECT_LE(t.frequency_hz(t.size() - 1), 81.2);
  }
  EXPECT_EQ(force, 4);
  EXPECT_EQ(response, 8);
  EXPECT_EQ(tables[0].label, "FRdata.ForceControl(1)");
  EXPECT_EQ(tables[4].label, "FRdata.ResponseControl(1)");
  // The first response-controlled level holds about 5 m/s^2 (as the file's README says).
  EXPECT_NEAR(tables[4].response.mean(), 4.987, 0.01);
  EXPECT_NEAR(tables[4].phase_rad(0), -0.110716, 1e-6);
}

// The .mat layout's units entry that also says how the values were measured ('m/s^2 RMS'):
// before, "third entry is not a motion unit", and with the word deleted alone the amplitudes were
// read zero to peak (0.707 times the truth); now the factor, on the field it applies to.
TEST(SteppedSineMat, AUnitMeasuredRmsOrPeakToPeakIsToldItsFactor) {
  const auto write = [](const std::string& name, const char* units) {
    const auto path = testing::scratch_path("stepped_sine_test", name);
    mat_t* mat = Mat_CreateVer(path.c_str(), nullptr, MAT_FT_MAT5);
    EXPECT_NE(mat, nullptr);
    const char* fields[] = {"frequency", "force", "amplitude", "phase", "units"};
    size_t one[2] = {1, 1}, five[2] = {5, 1}, len[2] = {1, std::strlen(units)};
    matvar_t* arr = Mat_VarCreateStruct("ResponseControl", 2, one, fields, 5);
    double f[5] = {1, 2, 3, 4, 5}, ones[5] = {1, 1, 1, 1, 1}, zeros[5] = {0, 0, 0, 0, 0};
    double* values[4] = {f, ones, ones, zeros};
    for (int k = 0; k < 4; ++k) {
      Mat_VarSetStructFieldByName(
          arr, fields[k], 0,
          Mat_VarCreate(nullptr, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, five, values[k], 0));
    }
    Mat_VarSetStructFieldByName(
        arr, "units", 0,
        Mat_VarCreate(nullptr, MAT_C_CHAR, MAT_T_UTF8, 2, len, const_cast<char*>(units), 0));
    Mat_VarWrite(mat, arr, MAT_COMPRESSION_NONE);
    Mat_VarFree(arr);
    Mat_Close(mat);
    return path;
  };
  EXPECT_EQ(read_stepped_sine(write("zero_to_peak.mat", "Hz, N, m/s^2, rad"))[0].response(0), 1.0);
  const auto rms = write("rms.mat", "Hz, N, m/s^2 RMS, rad");
  EXPECT_EQ(input_error_of([&] { read_stepped_sine(rms); }),
            rms.string() +
                ": field 'ResponseControl(1).units' ('Hz, N, m/s^2 RMS, rad'): 'RMS' says how "
                "'ResponseControl(1).amplitude' was measured, not a unit: multiply its values by "
                "sqrt(2) = 1.4142 (an amplitude is read zero to peak, a sine's RMS times sqrt(2); "
                "read as it is, F_S comes out 0.707 times the truth), then write 'm/s^2'");
  const auto pp = write("pp.mat", "Hz, N pk-pk, m/s^2, rad");
  EXPECT_EQ(input_error_of([&] { read_stepped_sine(pp); }),
            pp.string() +
                ": field 'ResponseControl(1).units' ('Hz, N pk-pk, m/s^2, rad'): 'pk-pk' says how "
                "'ResponseControl(1).force' was measured, not a unit: halve its values (a force "
                "amplitude is read zero to peak), then write 'N'");
  // Joined to the unit ('g_rms': before, "then write ''", the 'g' lost; 'grms': "not a motion
  // unit", no factor), and a measure without a unit.
  for (const char* units : {"Hz, N, g_rms, rad", "Hz, N, grms, rad"}) {
    const auto joined = write("joined.mat", units);
    EXPECT_EQ(input_error_of([&] { read_stepped_sine(joined); }),
              joined.string() + ": field 'ResponseControl(1).units' ('" + units +
                  "'): 'rms' says how 'ResponseControl(1).amplitude' was measured, not a unit: "
                  "multiply its values by sqrt(2) = 1.4142 (an amplitude is read zero to peak, a "
                  "sine's RMS times sqrt(2); read as it is, F_S comes out 0.707 times the truth), "
                  "then write 'g'");
  }
  const auto bare = write("bare.mat", "Hz, N, RMS, rad");
  EXPECT_NE(input_error_of([&] {
              read_stepped_sine(bare);
            }).find("0.707 times the truth), then write its unit alone ('m/s^2', 'g', ...)"),
            std::string::npos);
}

// A truncated copy is refused as a damaged file (matio alone would read the levels before
// the cut and stop), naming the file.
TEST(SteppedSineMat, RefusesATruncatedFile) {
  std::ifstream in(
      testing::source_dir() + "/data/examples/brake-reuss-beam/forced_frequency_responses.mat",
      std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto path =
      testing::scratch_file("stepped_sine_test", "cut.mat", bytes.substr(0, bytes.size() / 2));
  const std::string m = input_error_of([&] { read_stepped_sine(path); });
  EXPECT_NE(m.find("cut.mat: not a valid MATLAB v5 file"), std::string::npos) << m;
}

TEST(SteppedSineMat, RefusesARecordWithoutTables) {
  const std::string m = input_error_of([] {
    read_stepped_sine(testing::source_dir() + "/data/examples/brake-reuss-beam/no-such.mat");
  });
  EXPECT_NE(m.find("no-such.mat"), std::string::npos);
}

}  // namespace
}  // namespace jointlab::data
