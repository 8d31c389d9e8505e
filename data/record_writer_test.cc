#include "jointlab/data/record_writer.h"

#include <cmath>
#include <filesystem>
#include <functional>
#include <random>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "jointlab/core/error.h"
#include "jointlab/data/csv_reader.h"
#include "jointlab/data/mat_file.h"
#include "jointlab/data/uff58.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::data {
namespace {

namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
  return testing::scratch_path("jointlab-writer-test", name);
}

// A CSV test file as a data-acquisition front end writes it: units in g and N, a time column.
std::string front_end_csv() {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::string text = "# test: rt\n# level: 2\ntime,acc1 [g],acc2 [m/s^2],hammer [N]\n";
  for (int k = 0; k < 400; ++k) {
    const double t = k / 5120.0;
    text += fmt::format("{:.9f},{:.6e},{:.6e},{:.4f}\n", t,
                        std::exp(-3 * t) * std::sin(2 * M_PI * 80.5 * t) + 1e-3 * noise(rng),
                        0.3 * noise(rng), k < 5 ? 300.0 * std::sin(M_PI * k / 5) : 0.0);
  }
  return text;
}

TEST(RecordWriter, CsvUffAsciiUffBinaryCsvRoundTrip) {
  const Record csv = parse_csv(front_end_csv(), "front.csv");
  const fs::path asc = scratch("a.uff"), bin = scratch("b.uff"), back = scratch("back.csv");
  write_uff58(asc, csv, false);
  const Record from_asc = read_uff58(asc);
  write_uff58(bin, from_asc, true);
  const Record from_bin = read_uff58(bin);
  write_csv_record(back, from_bin);
  const Record end = read_csv(back);

  ASSERT_EQ(end.channels.size(), 3u);
  // UFF stores dt with 7 significant digits (E13.6): fs to 5e-7.
  EXPECT_TRUE(testing::Close(end.fs, csv.fs, 5e-7)) << end.fs << " vs " << csv.fs;
  EXPECT_EQ(end.fs, from_bin.fs);  // CSV prints fs in full: exact
  EXPECT_EQ(end.t0, from_bin.t0);
  for (size_t c = 0; c < 3; ++c) {
    const Channel& a = csv.channels[c];
    EXPECT_EQ(end.channels[c].name, a.name);
    EXPECT_EQ(end.channels[c].quantity, a.quantity);
    for (Eigen::Index k = 0; k < a.samples.size(); ++k) {
      // Binary and CSV steps: bit for bit.
      ASSERT_EQ(from_bin.channels[c].samples[k], from_asc.channels[c].samples[k]) << c << k;
      ASSERT_EQ(end.channels[c].samples[k], from_bin.channels[c].samples[k]) << c << k;
      // The ASCII step: E20.12 prints 13 significant digits, half a unit <= 5e-13 relative.
      ASSERT_TRUE(testing::Close(end.channels[c].samples[k], a.samples[k], 5e-13, 1e-300))
          << c << k;
    }
  }
}

TEST(RecordWriter, CsvIsBitExact) {
  Record r;
  r.fs = 1.0 / 3.0e-4;
  r.t0 = -1.0 / 7.0;
  Eigen::VectorXd x(6);
  x << 1.0 / 3.0, -2.5e-300, 6.02214076e23, 0.0, -0.0, std::nextafter(1.0, 2.0);
  r.channels.push_back(Channel{"v3", Quantity::kVelocity, "m/s", x});
  r.channels.push_back(Channel{"odd, name \"q\"", std::nullopt, "", -x});
  r.metadata["date"] = "2024-05-01";
  r.metadata["bad key: x"] = "dropped";
  const fs::path file = scratch("exact.csv");
  write_csv_record(file, r);
  const Record back = read_csv(file);
  EXPECT_EQ(back.fs, r.fs);
  EXPECT_EQ(back.t0, r.t0);
  ASSERT_EQ(back.channels.size(), 2u);
  EXPECT_EQ(back.channels[1].name, "odd, name \"q\"");
  EXPECT_EQ(back.channels[0].unit, "m/s");
  for (size_t c = 0; c < 2; ++c) EXPECT_EQ(back.channels[c].samples, r.channels[c].samples);
  EXPECT_EQ(back.metadata.at("date"), "2024-05-01");
}

TEST(RecordWriter, WriteRecordByExtension) {
  Record r;
  r.fs = 100;
  r.channels.push_back(
      Channel{"1+Z", Quantity::kAcceleration, "", Eigen::VectorXd::LinSpaced(5, 0, 1)});
  for (const char* name : {"x.csv", "x.uff", "x.mat"}) {
    write_record(scratch(name), r);
    EXPECT_TRUE(fs::exists(scratch(name))) << name;
  }
  EXPECT_EQ(read_uff58(scratch("x.uff")).channels[0].name, "1+Z");
  EXPECT_EQ(read_mat(scratch("x.mat")).channels[0].samples, r.channels[0].samples);
  const std::string m = testing::input_error_of([&] { write_record(scratch("x.xls"), r); });
  EXPECT_NE(m.find("x.xls: cannot tell the format"), std::string::npos) << m;
  EXPECT_FALSE(fs::exists(scratch("x.xls")));
}

TEST(RecordWriter, RefusesWhatCsvCannotHold) {
  Record r;
  r.fs = 100;
  r.channels.push_back(Channel{"acc [1]", std::nullopt, "", Eigen::VectorXd::Ones(3)});
  EXPECT_NE(testing::input_error_of([&] {
              format_csv_record(r, "o.csv");
            }).find("o.csv: channel name 'acc [1]'"),
            std::string::npos);
  r.channels[0].name = "Time";
  EXPECT_NE(testing::input_error_of([&] { format_csv_record(r, "o.csv"); }).find("not 'time'"),
            std::string::npos);
  r.channels[0].name = "a";
  r.channels[0].samples[1] = NAN;
  EXPECT_NE(
      testing::input_error_of([&] { format_csv_record(r, "o.csv"); }).find("holds NaN or Inf"),
      std::string::npos);
  r.fs = 0;
  EXPECT_NE(
      testing::input_error_of([&] { format_csv_record(r, "o.csv"); }).find("sampling rate 0 Hz"),
      std::string::npos);
}

}  // namespace
}  // namespace jointlab::data
