#include "jointlab/data/backbone_table.h"

#include <string>
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
  const BackboneTable t = read_backbone_table(p);
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
                                "damping_std\n2,10,0.01,0.001,1e-4\n1,11,0.02,0.002,0\n"));
  ASSERT_EQ(t.size(), 2);
  EXPECT_EQ(t.frequency_std_hz(0), 0.002);
  EXPECT_EQ(t.damping_std(0), 0.0);
  EXPECT_EQ(t.damping_std(1), 1e-4);
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
            "0.4,2,122.0,0.003,0,0.0,3\n"));
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
  };
  int i = 0;
  for (const auto& [text, expected] : cases) {
    const std::string name = "bad" + std::to_string(++i) + ".csv";
    const auto p = table(name, text);
    const std::string m = input_error_of([&] { read_backbone_table(p); });
    EXPECT_NE(m.find(expected), std::string::npos) << name << ": " << m;
  }
  const std::string m = input_error_of([] { read_backbone_table("/nonexistent/b.csv"); });
  EXPECT_NE(m.find("/nonexistent/b.csv"), std::string::npos) << m;
}

}  // namespace
}  // namespace jointlab::data
