#include "jointlab/data/backbone_table.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include <fmt/format.h>
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
  // Names are read case-blind: a re-cased table keeps its marks and its coverage factor (the
  // marked rows had been read as the mode's, and k = 3 stds as one sigma).
  const BackboneTable c = read_backbone_table(
      table("recased.csv",
            "Amplitude,Frequency_Hz,Damping_Ratio,Frequency_Std_Hz,Damping_Std,Harmonic,Exchange,"
            "Coverage_Factor\n"
            "5,122.1,-0.002,0.3,0.0003,0,1,3\n"
            "3,122.0,0.003,0.3,0.0003,0,0,3\n"
            "2,122.0,0.003,0.3,0.0003,0,0,3\n"),
      std::nullopt);
  ASSERT_EQ(c.size(), 2);
  EXPECT_EQ(c.coverage_factor, 3.0);
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
      // Under a per-cent header it is no ring-down either, and the header is not the fix.
      {"amplitude,frequency_hz,DAMPING_RATIO [%]\n1,10,0.5\n2,10,200\n",
       "bad14.csv:3: damping_ratio '200' % is 1 or more, critical damping: no ring-down"},
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

// A message a newcomer can act on: one line naming the file, the line or column, what is wrong
// and the fix (a lab's export, as the trial h22 wrote them, before: "no column 'amplitude'").
void expect_refusal(const std::string& name, const std::string& text,
                    std::optional<Quantity> quantity, const std::vector<std::string>& expected) {
  const auto p = table(name, text);
  const std::string m = input_error_of([&] { read_backbone_table(p, quantity); });
  for (const std::string& e : expected)
    EXPECT_NE(m.find(e), std::string::npos) << name << ": " << m;
  EXPECT_EQ(m.find('\n'), std::string::npos) << m;
}

TEST(BackboneTable, HeaderRefusalsNameTheColumnAndTheFix) {
  const std::string rows = "\n1,10,0.01\n2,10,0.02\n";
  // A unit in round brackets: the contract's units are in square ones.
  expect_refusal("h1.csv", "amplitude,frequency_hz,damping_ratio (%)" + rows, std::nullopt,
                 {"h1.csv:1: column 3 'damping_ratio (%)': write the unit in square brackets, "
                  "'damping_ratio [%]'"});
  expect_refusal("h2.csv", "Amplitude (g),frequency_hz,damping_ratio" + rows,
                 Quantity::kAcceleration,
                 {"h2.csv:1: column 1 'Amplitude (g)': write the unit in square brackets, "
                  "'amplitude [g]'"});
  // A lab's own names: each column that most likely meant one read is named with its new name.
  expect_refusal("h3.csv", "Amplitude,Freq (Hz),zeta" + rows, std::nullopt,
                 {"h3.csv:1: column 2 'Freq (Hz)': rename it 'frequency_hz [Hz]' (the unit in "
                  "square brackets); column 3 'zeta': rename it 'damping_ratio'"});
  // Parentheses that hold no unit of the column are not carried into the new name.
  expect_refusal("h4.csv", "amplitude,frequency (peak),damping_ratio" + rows, std::nullopt,
                 {"h4.csv:1: column 2 'frequency (peak)': rename it 'frequency_hz' ('peak' is "
                  "no unit of frequency_hz)"});
  // A loss factor is no damping ratio: the fix says how to turn one into the other.
  expect_refusal("h5.csv", "amplitude,frequency_hz,loss_factor" + rows, std::nullopt,
                 {"h5.csv:1: column 3 'loss_factor': a loss factor is twice the damping ratio: "
                  "halve its values and name the column 'damping_ratio'"});
  // Nothing to point at: the header to write.
  expect_refusal("h6.csv", "amplitude,frequency_hz,note" + rows, std::nullopt,
                 {"h6.csv:1: no column 'damping_ratio' (a backbone table's header: "
                  "amplitude,frequency_hz,damping_ratio[,frequency_std_hz,damping_std]"});
  // Lines above the header without '#': not skipped (one may say what the numbers are).
  expect_refusal("h7.csv",
                 "Backbone export 2024-05-01\nSensor: 9003:3\n\n"
                 "amplitude,frequency_hz,damping_ratio" +
                     rows,
                 std::nullopt,
                 {"h7.csv:1: 'Backbone export 2024-05-01' is read as the header, but the header "
                  "row is line 4: start each line above it with '#', or delete them"});
  expect_refusal("h7b.csv", "Accelerometer 9003:3\namplitude,frequency_hz,damping_ratio" + rows,
                 std::nullopt,
                 {"h7b.csv:1: 'Accelerometer 9003:3' is read as the header, but the header row "
                  "is line 2"});
  expect_refusal("h8.csv", "1,10,0.01\n2,10,0.02\n", std::nullopt,
                 {"h8.csv:1: the first row is numbers, not a header: add the header row"});
  // Case-blind names: two columns that both read as one are refused, naming both.
  expect_refusal("h9.csv", "amplitude,Amplitude,frequency_hz,damping_ratio\n1,1,10,0.01\n",
                 std::nullopt,
                 {"h9.csv:1: columns 1 'amplitude' and 2 'Amplitude' are both amplitude: keep "
                  "one"});
  // Units are case-sensitive: a unit that differs only in case is named, not read.
  expect_refusal("h10.csv", "amplitude [G],frequency_hz,damping_ratio" + rows,
                 Quantity::kAcceleration,
                 {"h10.csv:1: column 'amplitude [G]': unknown unit 'G': write 'amplitude [g]' "
                  "(units are case-sensitive; an acceleration amplitude takes m/s^2, mm/s^2, "
                  "in/s^2, g or mg)"});
  expect_refusal("h11.csv", "amplitude [parsec],frequency_hz,damping_ratio" + rows,
                 Quantity::kDisplacement,
                 {"h11.csv:1: column 'amplitude [parsec]': unknown unit 'parsec': a "
                  "displacement amplitude takes m, mm, um or in (SI m)"});
}

// The header a refusal suggests for an amplitude is one the --amplitude it names reads: followed
// as written (the header, and the --amplitude where the message names another), the same table
// reads. Before, a unit of another kind was suggested whatever --amplitude said: 'Amplitude (mm)'
// with --amplitude modal was told to write 'amplitude [mm]', which the same run then refused
// ("unit 'mm' refused: a modal amplitude ... takes no unit"), and with --amplitude velocity
// likewise ("unit 'mm' measures displacement"). A force's unit, which no --amplitude reads, is
// refused without a header to write.
TEST(BackboneTable, ASuggestedAmplitudeHeaderIsOneTheNamedAmplitudeReads) {
  const std::string rows = ",frequency_hz,damping_ratio\n1,10,0.01\n2,10,0.02\n";
  const std::vector<std::optional<Quantity>> kinds = {std::nullopt, Quantity::kDisplacement,
                                                      Quantity::kVelocity, Quantity::kAcceleration};
  const auto kind_named = [](const std::string& m, std::optional<Quantity> q) {
    const std::string needs = "needs --amplitude ";
    const size_t at = m.find(needs);
    if (at == std::string::npos) return q;
    const std::string word =
        m.substr(at + needs.size(), m.find_first_of(" ;", at + needs.size()) - (at + needs.size()));
    return parse_quantity(word);
  };
  int n = 0;
  for (const std::string header : {"Amplitude (mm)", "Amp (m/s^2)", "amplitude (mm/s)", "Amp [g]",
                                   "Amplitude (G)", "amp (MM/S)"}) {
    for (const std::optional<Quantity> q : kinds) {
      const std::string name = "k" + std::to_string(++n) + ".csv";
      const std::string m =
          input_error_of([&] { read_backbone_table(table(name, header + rows), q); });
      SCOPED_TRACE(name + ": " + m);
      ASSERT_FALSE(m.empty());
      EXPECT_EQ(m.find('\n'), std::string::npos);
      const size_t open = m.find("'amplitude [");
      ASSERT_NE(open, std::string::npos);
      const std::string suggested = m.substr(open + 1, m.find('\'', open + 1) - open - 1);
      const std::optional<Quantity> then = kind_named(m, q);
      ASSERT_TRUE(then || m.find("needs --amplitude") == std::string::npos);
      try {
        EXPECT_EQ(read_backbone_table(table("f" + name, suggested + rows), then).size(), 2);
      } catch (const InputError& e) {
        ADD_FAILURE() << "followed, '" << suggested << "' with --amplitude "
                      << (then ? quantity_name(*then) : "modal") << ": " << e.what();
      }
    }
  }
  expect_refusal("k_modal.csv", "Amplitude (mm)" + rows, std::nullopt,
                 {"k_modal.csv:1: column 1 'Amplitude (mm)': unit 'mm' refused: a modal amplitude "
                  "(--amplitude modal) takes no unit; a displacement amplitude needs --amplitude "
                  "displacement with --dof and the header 'amplitude [mm]'"});
  expect_refusal("k_velocity.csv", "Amplitude (mm)" + rows, Quantity::kVelocity,
                 {"k_velocity.csv:1: column 1 'Amplitude (mm)': unit 'mm' measures displacement, "
                  "the amplitude is a velocity (--amplitude velocity, SI unit m/s); a "
                  "displacement amplitude needs --amplitude displacement and the header "
                  "'amplitude [mm]'"});
  // A case slip in round brackets names the spelling: 'Amplitude (G)' was told to rename it
  // 'amplitude' ("'G' is no unit of amplitude"), and the table so renamed was read in m/s^2,
  // 9.81 times too small, without a word.
  expect_refusal("k_slip.csv", "Amplitude (G)" + rows, Quantity::kAcceleration,
                 {"k_slip.csv:1: column 1 'Amplitude (G)': write the unit in square brackets, "
                  "'amplitude [g]' (units are case-sensitive: 'G' is written 'g')"});
  // In square brackets the refusal names the --amplitude that reads the unit too.
  expect_refusal("k_square.csv", "amplitude [mm/s]" + rows, std::nullopt,
                 {"k_square.csv:1: column 'amplitude [mm/s]': unit 'mm/s' refused: a modal "
                  "amplitude (--amplitude modal) takes no unit; a velocity amplitude needs "
                  "--amplitude velocity with --dof"});
  // A force: no --amplitude reads it, and no header is suggested.
  for (const std::string header : {"Amplitude (N)", "amplitude [kN]"}) {
    const std::string m = input_error_of(
        [&] { read_backbone_table(table("k_force.csv", header + rows), Quantity::kVelocity); });
    EXPECT_NE(m.find("measures force, the amplitude is a velocity (--amplitude velocity, SI unit "
                     "m/s); no --amplitude reads a force: the amplitude is the response's"),
              std::string::npos)
        << m;
    for (const char* suggestion : {"the header '", "rename it", "square brackets, '"})
      EXPECT_EQ(m.find(suggestion), std::string::npos) << m;
  }
}

// A case slip of any spelling core/units.h reads is named with the spelling to write, and that
// spelling reads as the same unit. Before, the reader kept its own copy of the unit list, without
// micron, µm, m/s2, mm/s2, in/s2, m/s² or µm/s: 'amplitude [Micron]' was told "a displacement
// amplitude takes m, mm, um or in (SI m)", which does not name the unit meant.
TEST(BackboneTable, ACaseSlipOfAnyUnitSpellingIsNamed) {
  const std::string rows = ",frequency_hz,damping_ratio\n1,10,0.01\n2,10,0.02\n";
  int n = 0;
  for (Quantity q : {Quantity::kDisplacement, Quantity::kVelocity, Quantity::kAcceleration}) {
    for (const std::string& spelling : unit_spellings(q)) {
      std::string slip = spelling;
      for (char& c : slip) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
      if (slip == spelling || parse_unit(slip)) continue;
      const std::string name = "slip" + std::to_string(++n) + ".csv";
      const std::string m = input_error_of(
          [&] { read_backbone_table(table(name, "amplitude [" + slip + "]" + rows), q); });
      const std::string says = "unknown unit '" + slip + "': write 'amplitude [";
      const size_t at = m.find(says);
      ASSERT_NE(at, std::string::npos) << spelling << ": " << m;
      const size_t from = at + says.size();
      const auto named = parse_unit(m.substr(from, m.find(']', from) - from));
      ASSERT_TRUE(named.has_value()) << m;
      EXPECT_EQ(named->quantity, q) << m;
      EXPECT_EQ(named->to_si, parse_unit(spelling)->to_si) << m;
    }
  }
  EXPECT_GE(n, 14);
  expect_refusal("micron.csv", "amplitude [Micron]" + rows, Quantity::kDisplacement,
                 {"micron.csv:1: column 'amplitude [Micron]': unknown unit 'Micron': write "
                  "'amplitude [micron]' (units are case-sensitive; a displacement amplitude takes "
                  "m, mm, um or in)"});
}

// What cannot be read wrong is read: names case-blind (as a test file's "time"), and a
// spreadsheet's rows of empty cells (",,") skipped like blank lines, wherever they are.
TEST(BackboneTable, ReadsNamesCaseBlindAndSkipsRowsOfEmptyCells) {
  const BackboneTable t = read_backbone_table(
      table("caps.csv",
            "Amplitude,Frequency_Hz,DAMPING_RATIO [%],\n1,10,1,\n,,,\n2,11,2,\n , ,,\n,,,\n"),
      std::nullopt);
  ASSERT_EQ(t.size(), 2);
  EXPECT_EQ(t.frequency_hz(1), 11.0);
  EXPECT_DOUBLE_EQ(t.damping_ratio(1), 0.02);
  // A row with some cells empty is no blank row: refused, naming the empty column.
  expect_refusal("partly.csv", "amplitude,frequency_hz,damping_ratio\n1,10,0.01\n2,,0.01\n",
                 std::nullopt,
                 {"partly.csv:3: column 2 'frequency_hz' is empty: fill it or delete the row"});
}

// A decimal comma is never read as a decimal point ("1,234" may be a thousand) nor as a
// separator (the row would be read shifted): refused, naming the cell, the line and the fix.
TEST(BackboneTable, RefusesDecimalCommasNamingTheFix) {
  expect_refusal("c1.csv", "amplitude;frequency_hz;damping_ratio\n1e-06;121,85;0,0002\n",
                 std::nullopt,
                 {"c1.csv:2: decimal comma in '121,85' (column 2 'frequency_hz') with ';' "
                  "separators: write numbers with a decimal point, '121.85'"});
  expect_refusal("c2.csv", "amplitude\tfrequency_hz\tdamping_ratio\n1\t121\t0.001\n1,5\t1\t0.1\n",
                 std::nullopt,
                 {"c2.csv:3: decimal comma in '1,5' (column 1 'amplitude') with tab separators"});
  expect_refusal("c3.csv", "amplitude,frequency_hz,damping_ratio\n1,\"121,85\",0.001\n",
                 std::nullopt, {"c3.csv:2: decimal comma in '121,85'", "with ',' separators"});
  expect_refusal("c4.csv", "amplitude,frequency_hz,damping_ratio\n1e-06,121,85,0,0002\n",
                 std::nullopt,
                 {"c4.csv:2: 5 cells, the header names 3: decimal commas with ',' separators "
                  "split each number in two (write numbers with a decimal point"});
  expect_refusal("c5.csv", "amplitude;frequency_hz;damping_ratio\n1;10;0.01;7\n", std::nullopt,
                 {"c5.csv:2: 4 cells, the header names 3: a column without a name"});
}

// An uncertainty of the frequency or the damping under a name the reader does not know is
// refused, not ignored: the fit would weigh the points by its floors while the user believes
// the stated uncertainties are used.
TEST(BackboneTable, RefusesUncertaintiesUnderOtherNames) {
  const std::string rows = "\n1,10,0.01,0.1,0.001\n2,10,0.02,0.1,0.001\n";
  expect_refusal("s1.csv",
                 "amplitude,frequency_hz,damping_ratio,freq_std_hz,damping_std_rel" + rows,
                 std::nullopt,
                 {"s1.csv:1: column 4 'freq_std_hz': rename it 'frequency_std_hz' (one standard "
                  "deviation in Hz); column 5 'damping_std_rel': rename it 'damping_std' (one "
                  "standard deviation of the damping ratio, absolute: a relative one times "
                  "damping_ratio)",
                  "an uncertainty under another name is not read"});
  expect_refusal("s3.csv",
                 "amplitude,frequency_hz,damping_ratio,frequency_std_hz,zeta err [%]" + rows,
                 std::nullopt, {"s3.csv:1: column 5 'zeta err [%]': rename it 'damping_std [%]'"});
  expect_refusal("s4.csv", "amplitude,frequency_hz,damping_ratio,frequency_std_hz,note" + rows,
                 std::nullopt,
                 {"s4.csv:1: give both frequency_std_hz and damping_std, or neither (the table "
                  "has frequency_std_hz alone)"});
  // With both read, a further one is a further column; an amplitude's is not used by the update.
  const auto both = read_backbone_table(
      table("s5.csv",
            "amplitude,frequency_hz,damping_ratio,frequency_std_hz,damping_std,damping_std_rel\n"
            "1,10,0.01,0.1,0.001,0.1\n2,10,0.02,0.1,0.002,0.1\n"),
      std::nullopt);
  EXPECT_EQ(both.damping_std(1), 0.002);
  // A further column that names no frequency or damping is ignored, as the contract says,
  // whatever it sounds like: 'sigma' may be a decay rate; 'interrupted' holds no 'err'.
  for (const char* further : {"sigma", "fit_error", "interrupted", "temp_sd"}) {
    EXPECT_EQ(
        read_backbone_table(table("s7.csv", std::string("amplitude,frequency_hz,damping_ratio,") +
                                                further + "\n1,10,0.01,5\n2,10,0.02,5\n"),
                            std::nullopt)
            .size(),
        2)
        << further;
  }
  EXPECT_EQ(read_backbone_table(table("s6.csv",
                                      "amplitude,frequency_hz,damping_ratio,amplitude_std\n"
                                      "1,10,0.01,0.1\n2,10,0.02,0.1\n"),
                                std::nullopt)
                .size(),
            2);
}

// A lab's long file: several hits one under another, told apart by a column naming the hit.
// Read as one curve, the hits' offsets from one another looked like the model's misfit (six
// hits of a beam, Kt and Fs scattered by 0.4 % and 1 % between them: one file per hit gave
// Fs -0.30 % +/- 0.19 % and named the scatter between the hits; the same rows in one file
// with a 'hit' column stated no sigma and named no cause, and with 2 % and 3 % scatter named
// the structure's own damping instead). Refused, naming the fix.
TEST(BackboneTable, RefusesSeveralCurvesInOneFile) {
  const std::string rows =
      "1,1e-5,93.75,6.5e-4\n1,3e-5,93.70,7.0e-4\n2,1.2e-5,93.74,6.6e-4\n"
      "2,3.3e-5,93.69,7.1e-4\n";
  expect_refusal("long.csv", "hit,amplitude,frequency_hz,damping_ratio\n" + rows, std::nullopt,
                 {"long.csv:4: column 1 'hit' changes from '1' (line 2) to '2' here: the file "
                  "holds 2 curves (2 values of 'hit'), and a backbone table is one curve, one hit "
                  "or test, per file",
                  "write each hit's rows to a file of its own"});
  // Any name that labels a hit or test, any case, with a number or id word after it.
  for (const char* label : {"Test", "run_no", "Hit #", "record_id", "file_name", "shot number"}) {
    expect_refusal("label.csv",
                   std::string(label) + ",amplitude,frequency_hz,damping_ratio\n" + rows,
                   std::nullopt, {"label.csv:4: column 1 '" + std::string(label) + "' changes"});
  }
  // One value throughout is one curve; a value per row (a stepped sine's run per level) labels
  // points, not curves; other names are further columns, ignored.
  const auto one =
      read_backbone_table(table("one.csv",
                                "hit,amplitude,frequency_hz,damping_ratio\n3,1e-5,93.75,6.5e-4\n"
                                "3,3e-5,93.70,7.0e-4\n3,5e-5,93.6,8.0e-4\n"),
                          std::nullopt);
  EXPECT_EQ(one.size(), 3);
  const auto per_row =
      read_backbone_table(table("per_row.csv",
                                "run,amplitude,frequency_hz,damping_ratio\n1,1e-5,93.75,6.5e-4\n"
                                "2,3e-5,93.70,7.0e-4\n3,5e-5,93.6,8.0e-4\n"),
                          std::nullopt);
  EXPECT_EQ(per_row.size(), 3);
  for (const char* further : {"note", "hits_total", "testing", "level"}) {
    EXPECT_EQ(read_backbone_table(
                  table("further.csv",
                        std::string(further) + ",amplitude,frequency_hz,damping_ratio\n" + rows),
                  std::nullopt)
                  .size(),
              4)
        << further;
  }
}

// One hit's table given twice (the same file twice, or a copy re-saved) counted as two hits: its
// points weighed twice and the stated sigmas shrunk (two hits of a beam each given twice: K_T
// +/- 0.073 % -> 0.050 %, its error -0.196 % then 3.9 sigma, not 2.7). Refused, naming both;
// a copy is the same points to 1e-9 relative, whatever their digits; other hits are read in order.
TEST(BackboneTable, RefusesAHitGivenTwice) {
  const auto a = table("a.csv",
                       "amplitude,frequency_hz,damping_ratio\n1e-5,93.751234567891,"
                       "6.5e-4\n3e-5,93.70,7.0e-4\n");
  const auto b = table("b.csv",
                       "amplitude,frequency_hz,damping_ratio\n1e-5,93.76,6.5e-4\n"
                       "3e-5,93.71,7.0e-4\n");
  const auto copy = table("a_copy.csv",
                          "amplitude [m],frequency_hz,damping_ratio,note\n"
                          "3e-5,93.70,7.0e-4,x\n1e-5,93.7512345679,6.5e-4,y\n");
  const auto read = read_backbone_tables({a, b}, Quantity::kDisplacement);
  ASSERT_EQ(read.size(), 2u);
  EXPECT_EQ(read[1].source, b.string());
  EXPECT_EQ(input_error_of([&] {
              read_backbone_tables({a, b, a}, Quantity::kDisplacement);
            }),
            a.string() +
                ": given twice: a hit's table given twice counts as two hits, its points weighed "
                "twice and the stated sigmas shrunk by up to sqrt(2); give each hit once");
  EXPECT_NE(input_error_of([&] {
              read_backbone_tables({a, b, copy}, Quantity::kDisplacement);
            })
                .find(copy.string() + ": holds the same 2 points as " + a.string() +
                      " (every amplitude, frequency and damping equal): a hit's table given twice"),
            std::string::npos);
}

// A long file without a label column: hits one under another, each in time order (amplitude
// falling), the amplitude jumping back up where the next begins. Read as one curve, six such hits
// of a beam stated no sigma and named the structure's own damping as the cause (their scatter in
// K_T and F_S of 2 % and 3 %), where one file per hit named the scatter and stated a sigma.
// Refused at the first jump. The same rows in any other order (shuffled, sorted, a stepped sine
// up and down) are one curve, read; a few rows after a curve (fewer than four) are read too.
TEST(BackboneTable, RefusesHitsOneUnderAnotherWithoutALabel) {
  std::vector<std::string> rows;
  for (int hit = 0; hit < 3; ++hit) {
    for (int i = 0; i < 6; ++i) {
      rows.push_back(fmt::format("{:.6g},{:.6g},{:.6g}", 1e-4 * std::pow(0.5, i) * (1 + 0.05 * hit),
                                 93.0 + 0.1 * i + 0.01 * hit, 1e-3 * (1 - 0.1 * i)));
    }
  }
  const auto text = [&](const std::vector<size_t>& order) {
    std::string t = "amplitude,frequency_hz,damping_ratio\n";
    for (const size_t i : order) t += rows[i] + "\n";
    return t;
  };
  std::vector<size_t> order(rows.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  expect_refusal("hits.csv", text(order), std::nullopt,
                 {"hits.csv:8: the amplitude jumps back up here, from 3.125e-06 (line 7) to "
                  "0.000105, and the rows before and after run down in amplitude (3 runs of 6 "
                  "rows or more): several hits one under another? A backbone table is one curve",
                  "write each hit's rows to a file of its own; if the rows are one curve, sort "
                  "them by amplitude"});
  // Shuffled (a fixed permutation), sorted, and up then down: one curve each.
  std::vector<size_t> shuffled = order;
  for (size_t i = 0; i < shuffled.size(); ++i) std::swap(shuffled[i], shuffled[(7 * i + 3) % 18]);
  EXPECT_EQ(read_backbone_table(table("shuffled.csv", text(shuffled)), std::nullopt).size(), 18);
  std::vector<size_t> sorted = order;
  std::sort(sorted.begin(), sorted.end(),
            [&](size_t a, size_t b) { return std::stod(rows[a]) > std::stod(rows[b]); });
  EXPECT_EQ(read_backbone_table(table("sorted.csv", text(sorted)), std::nullopt).size(), 18);
  std::vector<size_t> up_down;
  for (int i = 5; i >= 0; --i) up_down.push_back(static_cast<size_t>(i));
  for (int i = 0; i < 6; ++i) up_down.push_back(static_cast<size_t>(6 + i));
  EXPECT_EQ(read_backbone_table(table("up_down.csv", text(up_down)), std::nullopt).size(), 12);
  std::vector<size_t> appended(order.begin(), order.begin() + 9);  // one hit and three rows
  EXPECT_EQ(read_backbone_table(table("appended.csv", text(appended)), std::nullopt).size(), 9);
  // Hits at three force levels, each sorted up in amplitude, their ranges overlapping.
  std::string levels = "amplitude,frequency_hz,damping_ratio\n";
  for (int hit = 0; hit < 3; ++hit)
    for (int i = 0; i < 6; ++i)
      levels += fmt::format("{:.6g},93,0.001\n", 1e-6 * std::pow(3.0, hit) * std::pow(2.0, i));
  expect_refusal("levels.csv", levels, std::nullopt,
                 {"levels.csv:8: the amplitude jumps back down here, from 3.2e-05 (line 7) to "
                  "3e-06, and the rows before and after run up in amplitude (3 runs of 6 rows"});
}

// A frequency in rad/s (an angular frequency, omega = 2 pi f): the fix is to divide by 2 pi.
// Before, 'frequency [rad/s]' was told to be renamed 'frequency_hz', which read its values, 2 pi
// times too high, as Hz; 'omega [rad/s]' was told only that no column 'frequency_hz' was found.
TEST(BackboneTable, AFrequencyInRadPerSecondIsToldToBeDividedByTwoPi) {
  const std::string rows = "\n1,940,0.01\n2,930,0.02\n";
  const std::string fix =
      "an angular frequency: divide its values by 2 pi (6.2832) and name the "
      "column 'frequency_hz'";
  expect_refusal("w1.csv", "amplitude,omega [rad/s],damping_ratio" + rows, std::nullopt,
                 {"w1.csv:1: column 2 'omega [rad/s]': " + fix});
  expect_refusal("w2.csv", "amplitude,frequency [rad/s],damping_ratio" + rows, std::nullopt,
                 {"w2.csv:1: column 2 'frequency [rad/s]': " + fix});
  expect_refusal("w3.csv", "amplitude,Angular frequency (rad/s),damping_ratio" + rows, std::nullopt,
                 {"w3.csv:1: column 2 'Angular frequency (rad/s)': " + fix});
  expect_refusal("w4.csv", "amplitude,frequency_hz [rad/s],damping_ratio" + rows, std::nullopt,
                 {"w4.csv:1: column 'frequency_hz [rad/s]': unit 'rad/s' refused: frequency_hz "
                  "is in Hz ([Hz] or no unit); a frequency in rad/s is 2 pi times the one in Hz: "
                  "divide its values by 2 pi (6.2832) and write 'frequency_hz [Hz]'"});
}

// An amplitude measured peak to peak or as RMS: renamed plainly ('amplitude_rms': "rename it
// 'amplitude'"), as the message told, it was read zero to peak and F_S came out 0.707 (RMS) or 2
// (peak to peak) times the truth, which no fit can tell. The fix names the factor first.
TEST(BackboneTable, APeakToPeakOrRmsAmplitudeIsToldItsFactor) {
  const std::string rows = "\n1,57.9,0.01\n2,57.8,0.02\n";
  const std::string halve =
      "halve its values (an amplitude is read zero to peak; peak-to-peak values read as they are "
      "give F_S twice the truth), then rename it ";
  const std::string root2 =
      "multiply its values by sqrt(2) = 1.4142 (an amplitude is read zero to peak, a sine's RMS "
      "times sqrt(2); read as it is, F_S comes out 0.707 times the truth), then rename it ";
  expect_refusal("r1.csv", "amplitude_rms,frequency_hz,damping_ratio" + rows, std::nullopt,
                 {"r1.csv:1: column 1 'amplitude_rms': " + root2 + "'amplitude'"});
  expect_refusal("r2.csv", "velocity_rms [mm/s],frequency_hz,damping_ratio" + rows,
                 Quantity::kVelocity,
                 {"r2.csv:1: column 1 'velocity_rms [mm/s]': " + root2 + "'amplitude [mm/s]'"});
  expect_refusal("p1.csv", "amp_pp [m/s],frequency_hz,damping_ratio" + rows, Quantity::kVelocity,
                 {"p1.csv:1: column 1 'amp_pp [m/s]': " + halve + "'amplitude [m/s]'"});
  expect_refusal("p2.csv", "Amplitude (peak-to-peak),frequency_hz,damping_ratio" + rows,
                 std::nullopt,
                 {"p2.csv:1: column 1 'Amplitude (peak-to-peak)': " + halve + "'amplitude'"});
  expect_refusal("p3.csv", "amplitude_p2p,frequency_hz,damping_ratio" + rows, std::nullopt,
                 {"p3.csv:1: column 1 'amplitude_p2p': " + halve + "'amplitude'"});
  // Zero to peak said in so many words is no other measure: told to rename alone.
  expect_refusal("z.csv", "amplitude_peak,frequency_hz,damping_ratio" + rows, std::nullopt,
                 {"z.csv:1: column 1 'amplitude_peak': rename it 'amplitude'"});
}

// Peak to peak as vibration meters write it (pk-pk, pk_pk), and a measure written beside the unit
// ('[mm/s pk-pk]', '[m/s RMS]'). Before, 'amplitude_pk-pk [m/s]' was told "rename it 'amplitude
// [m/s]'" and '[mm/s pk-pk]' only "unknown unit 'mm/s pk-pk'": followed, either was read zero to
// peak (F_S twice the truth, or 0.707 times). Now each is told its factor.
TEST(BackboneTable, PkPkAndAMeasureBesideTheUnitAreToldTheirFactor) {
  const std::string rows = "\n1,57.9,0.01\n2,57.8,0.02\n";
  const std::string halve =
      "halve its values (an amplitude is read zero to peak; peak-to-peak values read as they are "
      "give F_S twice the truth), then ";
  const std::string root2 =
      "multiply its values by sqrt(2) = 1.4142 (an amplitude is read zero to peak, a sine's RMS "
      "times sqrt(2); read as it is, F_S comes out 0.707 times the truth), then ";
  expect_refusal(
      "k1.csv", "amplitude_pk-pk [m/s],frequency_hz,damping_ratio" + rows, Quantity::kVelocity,
      {"k1.csv:1: column 1 'amplitude_pk-pk [m/s]': " + halve + "rename it 'amplitude [m/s]'"});
  expect_refusal("k2.csv", "Amplitude pk_pk,frequency_hz,damping_ratio" + rows, std::nullopt,
                 {"k2.csv:1: column 1 'Amplitude pk_pk': " + halve + "rename it 'amplitude'"});
  expect_refusal("u1.csv", "amplitude [mm/s pk-pk],frequency_hz,damping_ratio" + rows,
                 Quantity::kVelocity,
                 {"u1.csv:1: column 'amplitude [mm/s pk-pk]': 'pk-pk' says how it was measured, "
                  "not a unit: " +
                  halve + "write 'amplitude [mm/s]'"});
  expect_refusal("u2.csv", "amplitude [m/s RMS],frequency_hz,damping_ratio" + rows,
                 Quantity::kVelocity,
                 {"u2.csv:1: column 'amplitude [m/s RMS]': 'RMS' says how it was measured, not a "
                  "unit: " +
                  root2 + "write 'amplitude [m/s]'"});
  // After the unit: before, only "unit must be written as 'name [unit]'".
  expect_refusal(
      "a1.csv", "amplitude [m/s] (rms),frequency_hz,damping_ratio" + rows, Quantity::kVelocity,
      {"a1.csv:1: column 1 'amplitude [m/s] (rms)': " + root2 + "write 'amplitude [m/s]'"});
  expect_refusal(
      "a2.csv", "Velocity [mm/s] pk-pk,frequency_hz,damping_ratio" + rows, Quantity::kVelocity,
      {"a2.csv:1: column 1 'Velocity [mm/s] pk-pk': " + halve + "write 'amplitude [mm/s]'"});
}

// The measure joined to the unit ('[g_rms]', '[grms]'), 'p-p', and a unit in round brackets with
// the measure ('Amplitude (g RMS)'). Before, '[g_rms]' and '(g RMS)' were told to write
// 'amplitude' without the 'g': followed, values in g were read as m/s^2 (F_S 9.81 times off,
// noted only as a unit assumed); '[grms]' and '[mm/s p-p]' were refused as unknown units without
// the factor. Now each names the factor and keeps the unit.
TEST(BackboneTable, AMeasureJoinedToItsUnitKeepsTheUnitInTheFix) {
  const std::string rows = "\n1,57.9,0.01\n2,57.8,0.02\n";
  const std::string root2 =
      "multiply its values by sqrt(2) = 1.4142 (an amplitude is read zero to peak, a sine's RMS "
      "times sqrt(2); read as it is, F_S comes out 0.707 times the truth), then ";
  const std::string halve =
      "halve its values (an amplitude is read zero to peak; peak-to-peak values read as they are "
      "give F_S twice the truth), then ";
  expect_refusal("j1.csv", "amplitude [g_rms],frequency_hz,damping_ratio" + rows,
                 Quantity::kAcceleration,
                 {"j1.csv:1: column 'amplitude [g_rms]': 'rms' says how it was measured, not a "
                  "unit: " +
                  root2 + "write 'amplitude [g]'"});
  expect_refusal("j2.csv", "amplitude [grms],frequency_hz,damping_ratio" + rows,
                 Quantity::kAcceleration,
                 {"j2.csv:1: column 'amplitude [grms]': 'rms' says how it was measured, not a "
                  "unit: " +
                  root2 + "write 'amplitude [g]'"});
  expect_refusal("j3.csv", "amplitude [mm/s p-p],frequency_hz,damping_ratio" + rows,
                 Quantity::kVelocity,
                 {"j3.csv:1: column 'amplitude [mm/s p-p]': 'p-p' says how it was measured, not "
                  "a unit: " +
                  halve + "write 'amplitude [mm/s]'"});
  expect_refusal(
      "j4.csv", "Amplitude (g RMS),frequency_hz,damping_ratio" + rows, Quantity::kAcceleration,
      {"j4.csv:1: column 1 'Amplitude (g RMS)': " + root2 + "rename it 'amplitude [g]'"});
}

// A `process` (or `stepped-sine`) backbone read with another amplitude quantity than it was
// written in: its displacement_m column says which (amplitude = displacement_m (2 pi f)^p).
// Before, a velocity backbone read with --amplitude displacement went to the fit unsaid (its own
// files are in SI, so no unit note either); F_S scales by omega, 921 at 146.7 Hz.
TEST(BackboneTable, AProcessBackboneReadAsAnotherQuantityIsRefused) {
  std::string text = "time_s,amplitude,frequency_hz,damping_ratio,displacement_m\n";
  for (int i = 0; i < 4; ++i) {
    const double f = 146.65 + 0.5 * i, d = 2.8e-5 * std::pow(0.7, i);
    text += fmt::format("{},{:.10g},{:.10g},0.001,{:.10g}\n", 0.1 * i, 2 * M_PI * f * d, f, d);
  }
  const auto p = table("hit.acc.band1.csv", text);
  EXPECT_EQ(read_backbone_table(p, Quantity::kVelocity).size(), 4);
  EXPECT_EQ(read_backbone_table(p, std::nullopt).size(), 4);  // modal: nothing to compare
  EXPECT_EQ(input_error_of([&] { read_backbone_table(p, Quantity::kDisplacement); }),
            p.string() +
                ": its amplitude is a velocity (amplitude / displacement_m = 2 pi f on every row, "
                "as process and stepped-sine --amplitude velocity write it), but it is read as a "
                "displacement: "
                "give --amplitude velocity (F_S would come out scaled by 2 pi f)");
  EXPECT_NE(input_error_of([&] {
              read_backbone_table(p, Quantity::kAcceleration);
            }).find("its amplitude is a velocity"),
            std::string::npos);
}

}  // namespace
}  // namespace jointlab::data
