#include "jointlab/data/backbone_table.h"

#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "jointlab/tests/test_util.h"

namespace jointlab::data {
namespace {

using testing::input_error_of;

std::filesystem::path table(const std::string& name, const std::string& text) {
  return testing::scratch_file("jointlab_backbone_table_test", name, text);
}

TEST(BackboneTable, ReadsAnyRowOrderAndIgnoresFurtherColumns) {
  const auto p = table("ok.csv",
                       "# source: another lab\n"
                       "damping_ratio;amplitude [m];note;frequency_hz\n"
                       "7.0e-4;3e-5;x;93.70\n"
                       "6.5e-4;1e-5;y;93.75\n"
                       "\n"
                       "8.0e-4;9e-5;z;93.60\n");
  const BackboneTable t = read_backbone_table(p, Quantity::kDisplacement);
  EXPECT_EQ(t.source, p.string());
  ASSERT_EQ(t.size(), 3);
  // Sorted by amplitude, every column with its row.
  EXPECT_EQ(t.amplitude(0), 1e-5);
  EXPECT_EQ(t.frequency_hz(0), 93.75);
  EXPECT_EQ(t.damping_ratio(0), 6.5e-4);
  EXPECT_EQ(t.amplitude(2), 9e-5);
  EXPECT_EQ(t.damping_ratio(2), 8.0e-4);
  // No uncertainty columns: zeros (the update's floors).
  EXPECT_EQ(t.frequency_std_hz.size(), 3);
  EXPECT_EQ(t.frequency_std_hz.norm(), 0.0);
  EXPECT_EQ(t.damping_std.norm(), 0.0);
}

TEST(BackboneTable, ReadsTheUncertainties) {
  const BackboneTable t =
      read_backbone_table(table("std.csv",
                                "amplitude,frequency_hz,damping_ratio,frequency_std_hz,"
                                "damping_std\n2,10,0.01,0.001,1e-4\n1,11,0.02,0.002,0\n"),
                          std::nullopt);
  ASSERT_EQ(t.size(), 2);
  EXPECT_EQ(t.frequency_std_hz(0), 0.002);
  EXPECT_EQ(t.damping_std(0), 0.0);
  EXPECT_EQ(t.damping_std(1), 1e-4);
  EXPECT_EQ(t.coverage_factor, 1.0);  // no coverage_factor column: one sigma
  // A `process` backbone: its std columns are k sigma, k in its coverage_factor column, which is
  // read (the values themselves are kept as written) and must be one number >= 1.
  const std::string process_header =
      "time_s,amplitude,frequency_hz,damping_ratio,frequency_std_hz,damping_std,coverage_factor\n";
  const BackboneTable p = read_backbone_table(
      table("process.csv",
            process_header + "0.1,2,10,0.01,0.003,3e-4,3\n0.2,1,11,0.02,0.006,0,3\n"),
      std::nullopt);
  EXPECT_EQ(p.coverage_factor, 3.0);
  EXPECT_EQ(p.frequency_std_hz(0), 0.006);
  EXPECT_NE(input_error_of([&] {
              read_backbone_table(table("mixed.csv", process_header + "0.1,2,10,0.01,0.003,3e-4,3\n"
                                                                      "0.2,1,11,0.02,0.006,0,2\n"),
                                  std::nullopt);
            })
                .find("mixed.csv:3: coverage_factor '2' must be a finite number >= 1, the same on "
                      "every row"),
            std::string::npos);
}

// A `process` backbone's rows marked as not the mode's own are skipped before they are
// checked: an exchange point's apparent damping may be negative, a harmonic point follows a
// stronger mode's frequency. Unmarked rows (0, or no such column) are read.
TEST(BackboneTable, SkipsRowsMarkedHarmonicOrExchange) {
  const BackboneTable t = read_backbone_table(
      table("marked.csv",
            "time_s,amplitude,frequency_hz,damping_ratio,harmonic,exchange,coverage_factor\n"
            "0.1,5,122.1,-0.002,0,1,3\n"
            "0.2,4,244.0,0.006,2,0,3\n"
            "0.3,3,122.0,0.003,0,0,3\n"
            "0.4,2,122.0,0.003,0,0.0,3\n"),
      std::nullopt);
  ASSERT_EQ(t.size(), 2);
  EXPECT_EQ(t.amplitude(0), 2);
  EXPECT_EQ(t.amplitude(1), 3);
  EXPECT_EQ(t.damping_ratio.minCoeff(), 0.003);
}

// Every defect: one line naming the file and the line (the row as an editor numbers it).
TEST(BackboneTable, RefusesUnphysicalValuesWithFileAndLine) {
  const std::string header = "amplitude,frequency_hz,damping_ratio\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {header + "1,10,0.01\n2,10,-0.001\n", "bad1.csv:3: damping_ratio '-0.001' must be"},
      {header + "1,10,0.01\n2,10,0\n", "bad2.csv:3: damping_ratio '0' must be a finite number > 0"},
      {header + "1,10,0.01\n0,10,0.01\n", "bad3.csv:3: amplitude '0' must be"},
      {header + "1,nan,0.01\n2,10,0.01\n", "bad4.csv:2: frequency_hz 'nan' must be"},
      {header + "1,10,0.01\n2,inf,0.01\n", "bad5.csv:3: frequency_hz 'inf'"},
      {header + "1,10,0.01\n2,-10,0.01\n", "bad6.csv:3: frequency_hz '-10'"},
      {header + "1,10,0.01\n2,10\n", "bad7.csv:3: 2 cells, the header needs at least 3"},
      {header + "1,10,0.01\n", "bad8.csv: a backbone needs at least two points, the table has 1"},
      {"amplitude,frequency_hz\n1,10\n2,10\n", "bad9.csv:1: no column 'damping_ratio'"},
      {"amplitude,frequency_hz,damping_ratio,frequency_std_hz\n1,10,0.01,1\n2,10,0.01,1\n",
       "bad10.csv:1: give both frequency_std_hz and damping_std"},
      {"amplitude,frequency_hz,damping_ratio,frequency_std_hz,damping_std\n1,10,0.01,1,-1\n",
       "bad11.csv:2: damping_std '-1' must be a finite number >= 0"},
      {header + "1,10,abc\n2,10,0.01\n", "bad12.csv:2: damping_ratio 'abc'"},
      // Per cent without its unit: 4.85 (%) read as a fraction is no ring-down.
      {header + "1,10,0.5\n2,10,4.85\n",
       "bad13.csv:3: damping_ratio '4.85' is not a fraction below 1; per cent? write the header "
       "as 'damping_ratio [%]'"},
  };
  int i = 0;
  for (const auto& [text, expected] : cases) {
    const std::string name = "bad" + std::to_string(++i) + ".csv";
    const auto p = table(name, text);
    const std::string m = input_error_of([&] { read_backbone_table(p, std::nullopt); });
    EXPECT_NE(m.find(expected), std::string::npos) << name << ": " << m;
  }
  const std::string m =
      input_error_of([] { read_backbone_table("/nonexistent/b.csv", std::nullopt); });
  EXPECT_NE(m.find("/nonexistent/b.csv"), std::string::npos) << m;
}

// A unit in brackets is converted or refused, never ignored (before, `damping_ratio [%]` was read
// as a fraction and the fit targeted 100 times the damping). Per cent: divided by 100; the
// amplitude's unit converted to SI when it measures the caller's quantity. The converted values
// are one rounding of a product away from the decimal ones: EXPECT_DOUBLE_EQ (4 ulps).
TEST(BackboneTable, ConvertsPerCentAndAmplitudeUnitsAndRefusesTheRest) {
  const BackboneTable t = read_backbone_table(
      table("units.csv",
            "amplitude [mm/s],frequency_hz [Hz],damping_ratio [%],frequency_std_hz [Hz],"
            "damping_std [%]\n2,93.7,0.07,0.01,0.002\n1,93.8,0.06,0.01,0\n"),
      Quantity::kVelocity);
  ASSERT_EQ(t.size(), 2);
  EXPECT_DOUBLE_EQ(t.amplitude(0), 1e-3);
  EXPECT_DOUBLE_EQ(t.amplitude(1), 2e-3);
  EXPECT_DOUBLE_EQ(t.damping_ratio(0), 6e-4);
  EXPECT_DOUBLE_EQ(t.damping_ratio(1), 7e-4);
  EXPECT_DOUBLE_EQ(t.damping_std(1), 2e-5);
  EXPECT_EQ(t.frequency_hz(1), 93.7);
  EXPECT_EQ(t.amplitude_unit, "mm/s");  // as given, for the report
  const BackboneTable f = read_backbone_table(
      table("fraction.csv", "amplitude,frequency_hz,damping_ratio [1]\n1,10,0.01\n2,10,0.02\n"),
      std::nullopt);
  EXPECT_EQ(f.damping_ratio(1), 0.02);
  EXPECT_EQ(f.amplitude_unit, "");  // none given: SI assumed, which the report then says
  EXPECT_FALSE(f.written_by_jointlab);
  EXPECT_TRUE(read_backbone_table(table("ours.csv",
                                        "amplitude,frequency_hz,damping_ratio,coverage_factor\n"
                                        "1,10,0.01,3\n2,10,0.02,3\n"),
                                  std::nullopt)
                  .written_by_jointlab);

  // Each refusal: one line naming the file and header line, the column and the unit.
  const std::string rows = "\n1,10,0.01\n2,10,0.01\n";
  const std::vector<std::tuple<std::string, std::optional<Quantity>, std::string>> cases = {
      {"amplitude,frequency_hz [rad/s],damping_ratio", Quantity::kVelocity,
       "u1.csv:1: column 'frequency_hz [rad/s]': unit 'rad/s' refused: frequency_hz is in Hz"},
      {"amplitude,frequency_hz,damping_ratio [dB]", Quantity::kVelocity,
       "u2.csv:1: column 'damping_ratio [dB]': unit 'dB' refused: damping_ratio is a fraction"},
      {"amplitude [mm],frequency_hz,damping_ratio", Quantity::kVelocity,
       "u3.csv:1: column 'amplitude [mm]': unit 'mm' measures displacement, the amplitude is a "
       "velocity"},
      {"amplitude [m],frequency_hz,damping_ratio", std::nullopt,
       "u4.csv:1: column 'amplitude [m]': unit 'm' refused: a modal amplitude"},
      {"amplitude [furlong],frequency_hz,damping_ratio", Quantity::kDisplacement,
       "u5.csv:1: column 'amplitude [furlong]': unknown unit 'furlong'"},
      {"amplitude,frequency_hz,damping_ratio,frequency_std_hz [%],damping_std", std::nullopt,
       "u6.csv:1: column 'frequency_std_hz [%]': unit '%' refused"},
      {"amplitude,frequency_hz,damping_ratio,frequency_std_hz,damping_std [ppm]", std::nullopt,
       "u7.csv:1: column 'damping_std [ppm]': unit 'ppm' refused"},
  };
  int i = 0;
  for (const auto& [header, quantity, expected] : cases) {
    const std::string name = "u" + std::to_string(++i) + ".csv";
    const std::string body = header.find("std") != std::string::npos
                                 ? header + "\n1,10,0.01,0.1,0.001\n2,10,0.01,0.1,0.001\n"
                                 : header + rows;
    const auto p = table(name, body);
    const std::string m = input_error_of([&] { read_backbone_table(p, quantity); });
    EXPECT_NE(m.find(expected), std::string::npos) << name << ": " << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  }
}

}  // namespace
}  // namespace jointlab::data
