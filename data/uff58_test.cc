#include "jointlab/data/uff58.h"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <numbers>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "jointlab/core/error.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::data {
namespace {

using jointlab::testing::Close;

std::filesystem::path example(const std::string& name) {
  return std::filesystem::path(jointlab::testing::source_dir()) / "data/examples/uff58" / name;
}

// The message of the InputError `f` throws; fails the test if it throws nothing or prints
// more than one line.
// One ASCII dataset 58 with the given record 6/7/9 pieces and data lines.
std::string dataset(const std::string& r6, const std::string& r7, const std::string& r9,
                    const std::string& data) {
  return "    -1\n    58\nID1\nNONE\nNONE\nNONE\nNONE\n" + r6 + "\n" + r7 + "\n" +
         "        17    0    0    0 Time                 s                   \n" + r9 + "\n" +
         "         0    0    0    0 NONE                 NONE                \n"
         "         0    0    0    0 NONE                 NONE                \n" +
         data + "    -1\n";
}

const std::string kR6Z =
    "    1         0    0         0 NONE               1   3 NONE               0   0";
const std::string kR7 = "         2         4         1  0.00000E+00  1.00000E-03  0.00000E+00";
const std::string kR9Acc = "        12    1    0    0 acc                  m/s^2               ";
const std::string kData4 = "  1.00000E+00  2.00000E+00 -3.00000E+00  4.00000E+00\n";

TEST(Uff58, AsciiAndBinarySamplesAgree) {
  const Record a = read_uff58(example("Sample_UFF58_ascii.uff"));
  const Record b = read_uff58(example("Sample_UFF58b_bin.uff"));
  ASSERT_EQ(a.channels.size(), 1u);
  ASSERT_EQ(b.channels.size(), 1u);
  EXPECT_EQ(a.channels[0].name, "Mic 01");
  EXPECT_EQ(b.channels[0].name, "Mic 01");
  EXPECT_EQ(a.channels[0].unit, "Pa");
  EXPECT_FALSE(a.channels[0].quantity.has_value());  // pressure: no jointlab quantity
  EXPECT_EQ(a.size(), 79292);
  EXPECT_EQ(b.size(), 79292);
  EXPECT_DOUBLE_EQ(a.fs, 1.0 / 1.52588e-5);
  EXPECT_DOUBLE_EQ(b.fs, a.fs);
  EXPECT_EQ(a.metadata.at("format"), "uff58");
  EXPECT_EQ(b.metadata.at("format"), "uff58b");
  // The ASCII file prints 6 significant digits (E13.5): half a unit in the last place is
  // at most 5e-6 of the value; float32 adds 6e-8.
  long worst = 0;
  double worst_rel = 0;
  for (Eigen::Index k = 0; k < a.size(); ++k) {
    const double x = a.channels[0].samples[k], y = b.channels[0].samples[k];
    ASSERT_TRUE(Close(x, y, 5.1e-6, 1e-300)) << "sample " << k;
    if (y != 0 && std::abs(x - y) / std::abs(y) > worst_rel) {
      worst_rel = std::abs(x - y) / std::abs(y);
      worst = k;
    }
  }
  RecordProperty("worst_relative_difference", fmt::format("{} at {}", worst_rel, worst));
}

TEST(Uff58, BinaryFloat64WithUnitG) {
  const Record r = read_uff58(example("binary8byte.uff"));
  ASSERT_EQ(r.channels.size(), 1u);
  const Channel& c = r.channels[0];
  EXPECT_EQ(c.name, "sine 5 Hz");  // scalar direction: the response entity name
  ASSERT_TRUE(c.quantity.has_value());
  EXPECT_EQ(*c.quantity, Quantity::kAcceleration);
  EXPECT_EQ(c.unit, "g");
  EXPECT_EQ(r.size(), 250);
  EXPECT_DOUBLE_EQ(r.fs, 100.0);
  // The first float64 values as `od -t f8` prints them (a float32-rounded sine in g):
  // SI samples are exactly 9.80665 times them.
  const double g_values[] = {
      0.0, 0.30901697278022766, 0.5877852439880371, 0.80901700258255, 0.9510564804077148, 1.0};
  for (int k = 0; k < 6; ++k) EXPECT_EQ(c.samples[k], 9.80665 * g_values[k]) << k;
  // A 5 Hz sine of unit amplitude throughout (the file's own phase drifts by ~1e-5).
  EXPECT_TRUE(Close(c.samples.cwiseAbs().maxCoeff(), 9.80665, 1e-6));
  for (Eigen::Index k = 0; k < r.size(); ++k) {
    const double expected = 9.80665 * std::sin(2 * std::numbers::pi * 5 * 0.01 * k);
    ASSERT_TRUE(Close(c.samples[k], expected, 0, 1e-3)) << k;
  }
}

TEST(Uff58, ShortLastLineAndUtf8Unit) {
  const Record r = read_uff58(example("time-history-not-all-columns-filled.uff"));
  ASSERT_EQ(r.channels.size(), 1u);
  EXPECT_EQ(r.size(), 13);
  EXPECT_DOUBLE_EQ(r.fs, 1.0 / 5e-5);
  ASSERT_TRUE(r.channels[0].quantity.has_value());
  EXPECT_EQ(*r.channels[0].quantity, Quantity::kAcceleration);  // "m/s²"
  EXPECT_DOUBLE_EQ(r.channels[0].samples[12], -5.84096);
  EXPECT_EQ(r.channels[0].name, "1x : m/s\u00b2");  // no node, no entity: ID line 1
}

TEST(Uff58, RefusesSpectraAndFrfs) {
  const std::string psd = example("sample_dataset58_psd.uff").string();
  const std::string m1 = testing::input_error_of([&] { read_uff58(psd); });
  EXPECT_NE(m1.find(psd + ":8:"), std::string::npos) << m1;
  EXPECT_NE(m1.find("function type 9 (power spectral density)"), std::string::npos) << m1;
  const std::string m2 =
      testing::input_error_of([&] { read_uff58(example("non_ascii_header.uff")); });
  EXPECT_NE(m2.find("function type 4 (frequency response function)"), std::string::npos) << m2;
}

TEST(Uff58, RefusesTruncatedDeclaredLength) {
  // Declares 2 508 876 points and holds 42: refused before anything that size is allocated.
  const std::string m =
      testing::input_error_of([] { read_uff58(example("dataset_milestone_in_header.uff")); });
  EXPECT_NE(m.find("dataset_milestone_in_header.uff:14:"), std::string::npos) << m;
  EXPECT_NE(m.find("2508876 points"), std::string::npos) << m;
}

TEST(Uff58, NodeDirectionNamesAndSeveralDatasets) {
  const std::string r6y =
      "    1         0    0         0 NONE              12  -5 NONE               0   0";
  const std::string r9f = "        13    0    1    0 force                N                   ";
  const Record r =
      parse_uff58(dataset(kR6Z, kR7, kR9Acc, kData4) + dataset(r6y, kR7, r9f, kData4), "two.uff");
  ASSERT_EQ(r.channels.size(), 2u);
  EXPECT_EQ(r.channels[0].name, "1+Z");
  EXPECT_EQ(r.channels[1].name, "12-RY");
  EXPECT_EQ(*r.channels[1].quantity, Quantity::kForce);
  EXPECT_EQ(r.metadata.at("12-RY.node"), "12");
  EXPECT_EQ(r.metadata.at("1+Z.direction"), "+Z");
  EXPECT_DOUBLE_EQ(r.fs, 1000.0);
  EXPECT_EQ(r.channels[0].samples[2], -3.0);
}

TEST(Uff58, SkipsOtherDatasets) {
  const std::string units = "    -1\n   164\n         1  SI\n    2\n  1.0 1.0 1.0\n    -1\n";
  const Record r = parse_uff58(units + dataset(kR6Z, kR7, kR9Acc, kData4), "u.uff");
  EXPECT_EQ(r.size(), 4);
}

TEST(Uff58, UnlabelledTypeIsSiAndUnknownLabelIsRefused) {
  const std::string none = "        11    1    0    0 v                    NONE                ";
  const Record r = parse_uff58(dataset(kR6Z, kR7, none, kData4), "v.uff");
  EXPECT_EQ(*r.channels[0].quantity, Quantity::kVelocity);
  const std::string ft = "        12    1    0    0 a                    ft/s^2              ";
  const std::string m =
      testing::input_error_of([&] { parse_uff58(dataset(kR6Z, kR7, ft, kData4), "f.uff"); });
  EXPECT_NE(m.find("f.uff:11: record 9: unknown acceleration unit 'ft/s^2'"), std::string::npos)
      << m;
  const std::string clash = "        12    1    0    0 a                    m/s                 ";
  const std::string m2 =
      testing::input_error_of([&] { parse_uff58(dataset(kR6Z, kR7, clash, kData4), "c.uff"); });
  EXPECT_NE(m2.find("c.uff:11: record 9: unit 'm/s' measures velocity"), std::string::npos) << m2;
}

TEST(Uff58, UnevenUniformAbscissaIsAccepted) {
  const std::string r7 = "         2         3         0  0.00000E+00  0.00000E+00  0.00000E+00";
  const Record r = parse_uff58(dataset(kR6Z, r7, kR9Acc, "  0.0 1.0  0.5 2.0  1.0 3.0\n"), "u.uff");
  EXPECT_DOUBLE_EQ(r.fs, 2.0);
  EXPECT_EQ(r.channels[0].samples[2], 3.0);
}

// The hostile-input list: each a one-line InputError naming the file and the line.
TEST(Uff58BadInput, HugeDeclaredSizeAscii) {
  const std::string r7 = "         2 999999999         1  0.00000E+00  1.00000E-03  0.00000E+00";
  const std::string m =
      testing::input_error_of([&] { parse_uff58(dataset(kR6Z, r7, kR9Acc, kData4), "h.uff"); });
  EXPECT_NE(m.find("h.uff:14: dataset 58 declares 999999999 points"), std::string::npos) << m;
}

TEST(Uff58BadInput, HugeDeclaredSizeBinary) {
  Record r;
  r.fs = 10;
  r.channels.push_back(Channel{"a", Quantity::kAcceleration, "", Eigen::VectorXd::Ones(4)});
  std::string bin = format_uff58(r, true);
  const std::string from = "         4         4         1";
  bin.replace(bin.find(from), from.size(), "         4 999999999         1");
  const std::string m = testing::input_error_of([&] { parse_uff58(bin, "hb.uff"); });
  EXPECT_NE(m.find("hb.uff:14: dataset 58b declares 999999999 points but only"), std::string::npos)
      << m;
}

TEST(Uff58BadInput, TruncatedBinary) {
  Record r;
  r.fs = 10;
  r.channels.push_back(Channel{"a", Quantity::kAcceleration, "", Eigen::VectorXd::Ones(100)});
  const std::string bin = format_uff58(r, true);
  const std::string m =
      testing::input_error_of([&] { parse_uff58(bin.substr(0, bin.size() - 300), "t.uff"); });
  EXPECT_NE(m.find("t.uff:14: dataset 58b declares 100 points"), std::string::npos) << m;
}

TEST(Uff58BadInput, TruncatedAscii) {
  const std::string m = testing::input_error_of(
      [&] { parse_uff58(dataset(kR6Z, kR7, kR9Acc, "  1.00000E+00  2.00000E+00\n"), "t.uff"); });
  EXPECT_NE(m.find("t.uff:15: dataset 58 starting at line 2 is truncated: 2 of 4"),
            std::string::npos)
      << m;
}

TEST(Uff58BadInput, NanAndInf) {
  const std::string m = testing::input_error_of(
      [&] { parse_uff58(dataset(kR6Z, kR7, kR9Acc, "  1.0 nan 2.0 3.0\n"), "n.uff"); });
  EXPECT_NE(m.find("n.uff:14: value 2 is nan"), std::string::npos) << m;
  Record r;
  r.fs = 10;
  r.channels.push_back(Channel{"a", Quantity::kAcceleration, "", Eigen::VectorXd::Ones(4)});
  std::string bin = format_uff58(r, true);
  const double inf = INFINITY;
  // The data block is the 4 x 8 bytes before "\n    -1\n"; value 3 is 16 bytes in.
  std::memcpy(bin.data() + bin.size() - 8 - 32 + 16, &inf, 8);
  const std::string m2 = testing::input_error_of([&] { parse_uff58(bin, "i.uff"); });
  EXPECT_NE(m2.find("i.uff:14: dataset 58b: value 3 is inf"), std::string::npos) << m2;
}

TEST(Uff58BadInput, NonMonotonicTime) {
  const std::string r7 = "         2         3         0  0.00000E+00  0.00000E+00  0.00000E+00";
  const std::string m = testing::input_error_of(
      [&] { parse_uff58(dataset(kR6Z, r7, kR9Acc, "  0.0 1.0  1.0 2.0  0.5 3.0\n"), "m.uff"); });
  EXPECT_NE(m.find("m.uff:14: uneven abscissa: point 3 at t = 0.5 does not increase"),
            std::string::npos)
      << m;
}

TEST(Uff58BadInput, DuplicateChannelNames) {
  const std::string m = testing::input_error_of([&] {
    parse_uff58(dataset(kR6Z, kR7, kR9Acc, kData4) + dataset(kR6Z, kR7, kR9Acc, kData4), "d.uff");
  });
  EXPECT_NE(m.find("d.uff:17: dataset 58 #2: two channels named '1+Z'"), std::string::npos) << m;
}

TEST(Uff58BadInput, ZeroSamplingInterval) {
  const std::string r7 = "         2         4         1  0.00000E+00  0.00000E+00  0.00000E+00";
  const std::string m =
      testing::input_error_of([&] { parse_uff58(dataset(kR6Z, r7, kR9Acc, kData4), "z.uff"); });
  EXPECT_NE(m.find("z.uff:9: record 7: abscissa increment 0 is not positive"), std::string::npos)
      << m;
}

TEST(Uff58BadInput, DifferentTimeBases) {
  const std::string r7b = "         2         4         1  0.00000E+00  2.00000E-03  0.00000E+00";
  const std::string m = testing::input_error_of([&] {
    parse_uff58(
        dataset(kR6Z, kR7, kR9Acc, kData4) +
            dataset("    1         0    0         0 NONE               2   3", r7b, kR9Acc, kData4),
        "b.uff");
  });
  EXPECT_NE(m.find("b.uff:17: dataset 58 #2: time base"), std::string::npos) << m;
}

TEST(Uff58BadInput, ComplexOrdinatesAndGarbage) {
  const std::string r7 = "         5         4         1  0.00000E+00  1.00000E-03  0.00000E+00";
  const std::string m =
      testing::input_error_of([&] { parse_uff58(dataset(kR6Z, r7, kR9Acc, kData4), "c.uff"); });
  EXPECT_NE(m.find("c.uff:9: record 7: complex ordinate data"), std::string::npos) << m;
  EXPECT_NE(testing::input_error_of([] {
              parse_uff58("hello\n", "g.uff");
            }).find("g.uff:1: expected '-1'"),
            std::string::npos);
  EXPECT_NE(testing::input_error_of([] { parse_uff58("", "e.uff"); }).find("e.uff: empty file"),
            std::string::npos);
  EXPECT_NE(testing::input_error_of([] {
              parse_uff58("    -1\n    58\nA\n", "s.uff");
            }).find("s.uff:3: dataset 58 starting at line 2 ends inside its header"),
            std::string::npos);
}

TEST(Uff58, WriterRoundTripsAsciiToPrintedPrecisionAndBinaryExactly) {
  Record r;
  r.fs = 3000.0;
  r.t0 = -0.01;
  Eigen::VectorXd x(7);
  x << 1.0 / 3.0, -2.5e-7, 123456.789012345678, 0.0, -1e-12, 9.80665, std::acos(-1.0);
  r.channels.push_back(Channel{"acc1", Quantity::kAcceleration, "m/s^2", x});
  r.channels.push_back(Channel{"3-Y", Quantity::kVelocity, "m/s", 2 * x});
  r.channels.push_back(Channel{"a long channel name", std::nullopt, "Pa", -x});
  const Record bin = parse_uff58(format_uff58(r, true), "b.uff");
  const Record asc = parse_uff58(format_uff58(r, false), "a.uff");
  for (const Record* back : {&bin, &asc}) {
    ASSERT_EQ(back->channels.size(), 3u);
    EXPECT_EQ(back->channels[0].name, "acc1");
    EXPECT_EQ(back->channels[1].name, "3-Y");
    EXPECT_EQ(back->channels[2].name, "a long channel name");
    EXPECT_EQ(*back->channels[1].quantity, Quantity::kVelocity);
    EXPECT_FALSE(back->channels[2].quantity.has_value());
    EXPECT_EQ(back->channels[2].unit, "Pa");
    // dt is printed with 7 significant digits (E13.6).
    EXPECT_TRUE(Close(back->fs, r.fs, 5e-7));
    EXPECT_TRUE(Close(back->t0, r.t0, 5e-7));
  }
  for (size_t c = 0; c < 3; ++c) {
    for (Eigen::Index k = 0; k < x.size(); ++k) {
      EXPECT_EQ(bin.channels[c].samples[k], r.channels[c].samples[k]);  // float64: exact
      // E20.12: 13 significant digits, half a unit in the last place <= 5e-13 relative.
      EXPECT_TRUE(Close(asc.channels[c].samples[k], r.channels[c].samples[k], 5e-13, 1e-300));
    }
  }
}

}  // namespace
}  // namespace jointlab::data
