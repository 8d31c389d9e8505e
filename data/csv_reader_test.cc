#include "jointlab/data/csv_reader.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>

#include <gtest/gtest.h>

#include "jointlab/core/error.h"
#include "jointlab/data/csv_lines.h"
#include "jointlab/tests/process_memory.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::data {
namespace {

// Expects parse_csv to throw InputError whose message contains every fragment.
void expect_error(const std::string& text, std::initializer_list<const char*> fragments) {
  try {
    parse_csv(text, "hit.csv");
    FAIL() << "no error for:\n" << text;
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "message is not one line: " << msg;
    for (const char* f : fragments) {
      EXPECT_NE(msg.find(f), std::string::npos) << "'" << f << "' not in: " << msg;
    }
  }
}

TEST(CsvReader, ReadsMetadataTimeAndUnits) {
  const Record r = parse_csv(
      "# test: T1\n# level: 2\ntime,acc1 [g],v [mm/s],hammer [N],raw\n"
      "0.0,1,2,3,4\n0.5,0.5,1,0,5\n1.0,0,0,0,6\n",
      "hit.csv");
  EXPECT_DOUBLE_EQ(r.fs, 2.0);
  EXPECT_DOUBLE_EQ(r.t0, 0.0);
  ASSERT_EQ(r.channels.size(), 4u);
  EXPECT_EQ(r.metadata.at("test"), "T1");
  EXPECT_EQ(r.channels[0].name, "acc1");
  EXPECT_EQ(r.channels[0].quantity, Quantity::kAcceleration);
  EXPECT_DOUBLE_EQ(r.channels[0].samples(0), 9.80665);
  EXPECT_DOUBLE_EQ(r.channels[1].samples(0), 2e-3);
  EXPECT_EQ(r.channels[2].quantity, Quantity::kForce);
  EXPECT_FALSE(r.channels[3].quantity.has_value());
  EXPECT_EQ(r.size(), 3);
}

// Round brackets that hold no unit are part of the name (a unit in them is refused, above).
TEST(CsvReader, RoundBracketsWithoutAUnitArePartOfTheName) {
  const Record r =
      parse_csv("time,pt3 (Z+) [m/s],pt4 (x),force (in)\n0,1,2,3\n0.1,2,3,4\n", "hit.csv");
  ASSERT_EQ(r.channels.size(), 3u);
  EXPECT_EQ(r.channels[2].name, "force (in)");  // input: 'in' is a word before it is inches
  EXPECT_EQ(r.channels[0].name, "pt3 (Z+)");
  EXPECT_EQ(r.channels[0].quantity, Quantity::kVelocity);
  EXPECT_EQ(r.channels[1].name, "pt4 (x)");
  EXPECT_FALSE(r.channels[1].quantity.has_value());
}

TEST(CsvReader, DetectsSemicolonAndTab) {
  for (const char* d : {";", "\t"}) {
    std::string text =
        std::string("time") + d + "x [m]\n0" + d + "1\n0.1" + d + "2\n0.2" + d + "3\n";
    const Record r = parse_csv(text, "hit.csv");
    ASSERT_EQ(r.channels.size(), 1u);
    EXPECT_NEAR(r.fs, 10.0, 1e-9);
    EXPECT_DOUBLE_EQ(r.channels[0].samples(2), 3.0);
  }
}

TEST(CsvReader, SampleRateFromMetadata) {
  const Record r = parse_csv("# fs: 100 Hz\nacc [m/s^2]\n1\n2\n3\r\n", "hit.csv");
  EXPECT_DOUBLE_EQ(r.fs, 100.0);
  EXPECT_EQ(r.size(), 3);
}

TEST(CsvReader, RoundedTimesAreUniform) {
  // 3 kHz printed with 5 decimals: rounding up to 5e-6 s, 1.5 % of a step; accepted.
  std::string text = "time,x\n";
  char buf[64];
  for (int k = 0; k < 1000; ++k) {
    std::snprintf(buf, sizeof buf, "%.5f,%d\n", k / 3000.0, k);
    text += buf;
  }
  const Record r = parse_csv(text, "hit.csv");
  EXPECT_NEAR(r.fs, 3000.0, 0.01);
}

TEST(CsvReader, BadInputsGiveOneLineErrors) {
  expect_error("", {"hit.csv", "empty file"});
  expect_error(std::string("time,x\n0,1\n\0\x01\x02", 15), {"hit.csv", "binary"});
  expect_error("time,x\n0,1\n0.1,2\n0.2,3\n0.35,4\n0.4,5\n", {"hit.csv:5", "not uniform"});
  expect_error("time,x\n0,1\n0.1,2\n0.2,3\n0.3,4\n0.4,5\n0.55,6\n0.65,7\n0.75,8\n",
               {"not uniform"});
  expect_error("time,x\n0,1\n0.1,2\n0.05,3\n", {"hit.csv:4", "does not increase"});
  expect_error("time,x,y\n0,1,2\n0.1,2\n", {"hit.csv:3", "2 fields", "header has 3"});
  expect_error("time,x\n0,1\n0.1,abc\n", {"hit.csv:3", "'x'", "'abc' is not a number"});
  expect_error("time,x\n0,1\n0.1,nan\n", {"hit.csv:3", "NaN"});
  expect_error("time,x\n0,1\n0.1,inf\n", {"hit.csv:3", "Inf"});
  expect_error("time,x,x\n0,1,2\n0.1,2,3\n", {"hit.csv:1", "two channels named 'x'"});
  expect_error("time,x [furlong]\n0,1\n0.1,2\n", {"hit.csv:1", "unknown unit 'furlong'"});
  // A unit in round brackets: 'acc1 (g)' had been a channel of that name with no unit, read as
  // m/s^2 under --quantity acceleration (9.81 times too small).
  expect_error("time,acc1 (g)\n0,1\n0.1,2\n",
               {"hit.csv:1",
                "column 'acc1 (g)': if 'g' is its unit, write it in square "
                "brackets, 'acc1 [g]'"});
  expect_error("time (s),x [m]\n0,1\n0.1,2\n", {"hit.csv:1", "'time [s]'"});
  expect_error("x,y\n1,2\n3,4\n", {"hit.csv:1", "no 'time' column"});
  expect_error("# fs: -5\nx\n1\n2\n", {"hit.csv:1", "fs"});
  expect_error("# fs: 0\nx\n1\n2\n", {"hit.csv:1", "fs"});
  expect_error("time,x\n0,1\n", {"hit.csv", "need at least 2"});
  expect_error("# only a comment\n", {"hit.csv", "no header"});
  // A trailing delimiter on one row is an empty field, not a style.
  expect_error("time,x\n0,1\n0.1,2,\n0.2,3\n", {"hit.csv:3", "3 fields where the header has 2"});
  expect_error("time,x,\n0,1,\n0.1,2,3\n", {"hit.csv:3", "3 fields where the header has 2"});
  // Names and values in messages are cut: a 1 MB unit gives a short message, and so does a
  // 1 MB channel name (refused: longer than kMaxChannelNameBytes).
  for (const auto& [header, fragment] :
       {std::pair{"time,a [" + std::string(1 << 20, 'u') + "]", "... (1048576 bytes)"},
        std::pair{"time," + std::string(1 << 20, 'a'),
                  "channel name of 1048576 bytes ('aaaaaaaaaa"}}) {
    try {
      parse_csv(header + "\n0,1\n0.1,x\n", "hit.csv");
      ADD_FAILURE() << "no error";
    } catch (const InputError& e) {
      EXPECT_LT(std::string(e.what()).size(), 300u);
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  }
}

TEST(CsvReader, TrailingDelimiterOnEveryLine) {
  const Record r = parse_csv("time,x,\n0,1,\n0.1,2,\n0.2,3,\n", "hit.csv");
  ASSERT_EQ(r.channels.size(), 1u);
  EXPECT_EQ(r.channels[0].samples, Eigen::Vector3d(1, 2, 3));
}

TEST(CsvReader, ManyChannels) {
  // 20 000 channels, 2 rows; the last name repeats the first, found in one pass.
  std::string header = "time", row0 = "0", row1 = "0.1";
  for (int c = 0; c < 20000; ++c) {
    const std::string k = std::to_string(c);
    header.append(",c").append(k);
    row0.append(",").append(k);
    row1 += ",1";
  }
  const Record r = parse_csv(header + "\n" + row0 + "\n" + row1 + "\n", "hit.csv");
  ASSERT_EQ(r.channels.size(), 20000u);
  EXPECT_EQ(r.channels[12345].name, "c12345");
  EXPECT_EQ(r.channels[12345].samples(0), 12345);
  expect_error(header + ",c0\n" + row0 + ",1\n" + row1 + ",1\n",
               {"hit.csv:1", "two channels named 'c0'"});
}

TEST(CsvReader, ReadsFromAFileAsFromText) {
  const std::string text = "# fs: 10\nx [mm]\n1\n2\n3\n";
  const std::string path =
      jointlab::testing::scratch_path("jointlab_csv_reader_test", "read.csv").string();
  std::FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  std::fwrite(text.data(), 1, text.size(), f);
  std::fclose(f);
  const Record a = read_csv(path), b = parse_csv(text, path);
  ASSERT_EQ(a.channels.size(), 1u);
  EXPECT_EQ(a.channels[0].samples, b.channels[0].samples);
  EXPECT_EQ(a.channels[0].samples, Eigen::Vector3d(1e-3, 2e-3, 3e-3));
  EXPECT_EQ(a.fs, 10);
  std::remove(path.c_str());
}

using jointlab::testing::memory_now;

TEST(CsvReader, ReadingCostsAboutTheSamplesBinarySize) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer keeps freed memory in quarantine";
#endif
  // 1e6 rows of time and two channels: 24 MB as doubles, 44 MB as text.
  const std::string path =
      jointlab::testing::scratch_path("jointlab_csv_reader_test", "memory.csv").string();
  {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fputs("time,a [m/s^2],b [m/s^2]\n", f);
    for (int k = 0; k < 1000000; ++k)
      std::fprintf(f, "%.6f,%.9e,%.9e\n", k * 1e-5, std::sin(k * 0.01), std::cos(k * 0.01));
    std::fclose(f);
  }
  // Reset the peak (Linux clear_refs 5), then read.
  std::ofstream("/proc/self/clear_refs") << "5";
  const double before = memory_now().second;
  const Record r = read_csv(path);
  const double peak = memory_now().first - before;
  std::remove(path.c_str());
  ASSERT_EQ(r.size(), 1000000);
  const double binary = 3 * 8e6;
  // Twice the binary size (the columns, and each channel's copy), plus 16 MB of mapped
  // text in flight; the whole text in memory (44 MB) or columns grown by doubling would
  // break it.
  EXPECT_LT(peak, 2 * binary + 16e6) << "peak " << peak / 1e6 << " MB";
}

// A header's "name [unit]" and "name (unit)": the name before the bracket and the unit inside,
// both trimmed; none where the bracket does not close the name (the modes table then reads the
// cell as no frequency column, split_name_unit refuses it naming the file and line).
TEST(CsvLines, SplitsANameFromTheUnitInItsBrackets) {
  using Split = std::optional<std::pair<std::string, std::string>>;
  EXPECT_EQ(split_square_brackets("Frequency [Hz]"), (Split{{"Frequency", "Hz"}}));
  EXPECT_EQ(split_square_brackets("  f [ kHz ]  "), (Split{{"f", "kHz"}}));
  EXPECT_EQ(split_square_brackets("Frequency [Hz"), std::nullopt);
  EXPECT_EQ(split_square_brackets("Frequency [Hz] mean"), std::nullopt);
  EXPECT_EQ(split_square_brackets("Frequency (Hz)"), std::nullopt);
  EXPECT_EQ(split_round_brackets("Freq (Hz)"), (Split{{"Freq", "Hz"}}));
  EXPECT_EQ(split_round_brackets("pt3 (Z+) (g)"), (Split{{"pt3 (Z+)", "g"}}));
  EXPECT_EQ(split_round_brackets("Freq (Hz"), std::nullopt);
  EXPECT_EQ(split_name_unit("acc1 [g]", "a.csv", 1),
            (std::pair<std::string, std::string>{"acc1", "g"}));
  EXPECT_EQ(split_name_unit("acc1", "a.csv", 1), (std::pair<std::string, std::string>{"acc1", ""}));
  EXPECT_THROW(split_name_unit("acc1 [g", "a.csv", 1), InputError);
}

}  // namespace
}  // namespace jointlab::data
