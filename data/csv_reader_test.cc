#include "jointlab/data/csv_reader.h"

#include <cstdio>

#include <gtest/gtest.h>

#include "jointlab/core/error.h"

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
  expect_error("x,y\n1,2\n3,4\n", {"hit.csv:1", "no 'time' column"});
  expect_error("# fs: -5\nx\n1\n2\n", {"hit.csv:1", "fs"});
  expect_error("# fs: 0\nx\n1\n2\n", {"hit.csv:1", "fs"});
  expect_error("time,x\n0,1\n", {"hit.csv", "need at least 2"});
  expect_error("# only a comment\n", {"hit.csv", "no header"});
}

}  // namespace
}  // namespace jointlab::data
